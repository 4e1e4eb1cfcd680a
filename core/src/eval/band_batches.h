// How evaluate's work over bands (rows of the last evaluated mip) is cut into batches: between
// batches the calling thread reports progress and reads the cancel flag.
#pragma once

#include <tbb/task_arena.h>

#include <algorithm>

namespace burnish {

/// The batch count for `bands` bands: at most 32 (progress in steps of about 3 %) and at least 4 where
/// there are 4 bands (a progress bar that moves), and otherwise two bands per worker thread in each
/// batch, so that every core has work in every batch (32 bands, a 512² map's mip 4, in batches of
/// one ran on one core).
inline int bandBatches(int bands) {
    const int threads = std::max(1, tbb::this_task_arena::max_concurrency());
    const int most = std::clamp(bands, 1, 32);
    return std::clamp(bands / (2 * threads), std::min(most, 4), most);
}

} // namespace burnish
