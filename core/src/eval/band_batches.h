// How evaluate's work over bands (rows of the last evaluated mip) is cut into batches: between
// batches the calling thread reports progress and reads the cancel flag.
#pragma once

#include <tbb/task_arena.h>

#include <algorithm>

namespace burnish {

/// The batch count for `bands` bands: at most 32 (progress in steps of about 3 %), and each batch at
/// least two bands per worker thread where there are that many, so that every core has work in
/// every batch (32 bands, a 512² map's mip 4, in batches of one ran on one core).
inline int bandBatches(int bands) {
    const int threads = std::max(1, tbb::this_task_arena::max_concurrency());
    return std::clamp(bands / (2 * threads), 1, std::min(std::max(bands, 1), 32));
}

} // namespace burnish
