// The one memory ceiling (util/memory.h) and the commands' estimates against the peaks measured with
// core/bench/command_memory.sh: every estimate within 1.5x of its measured peak, in both directions
// (update the figures with the bench when the code's memory moves).
#include <burnish/core/env/prefilter.h>
#include <burnish/core/eval/evaluate_report.h>
#include <burnish/core/util/memory.h>

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

namespace burnish {
namespace {

// Sets BURNISH_MEMORY_LIMIT for one scope.
struct LimitScope {
    explicit LimitScope(const char* value) {
        if (value)
            ::setenv("BURNISH_MEMORY_LIMIT", value, 1);
        else
            ::unsetenv("BURNISH_MEMORY_LIMIT");
    }
    ~LimitScope() { ::unsetenv("BURNISH_MEMORY_LIMIT"); }
};

void expectWithin(double estimate, double measured, const std::string& what) {
    EXPECT_LE(estimate, 1.5 * measured)
        << what << ": estimate " << estimate / 1e6 << " MB, measured " << measured / 1e6 << " MB";
    EXPECT_GE(estimate, measured / 1.5)
        << what << ": estimate " << estimate / 1e6 << " MB, measured " << measured / 1e6 << " MB";
}

TEST(Memory, TheLimitCapsWhatIsAvailableAndBadValuesAreErrors) {
    {
        LimitScope none(nullptr);
        // No limit: what the system has (read twice, so within what other processes move meanwhile).
        const auto usable = usableMemoryBytes();
        const auto available = availableMemoryBytes();
        ASSERT_TRUE(usable.ok());
        ASSERT_EQ(usable->has_value(), available.has_value());
        if (available) {
            EXPECT_GT(double(**usable), 0.5 * double(*available));
            EXPECT_LT(double(**usable), 2.0 * double(*available));
        }
    }
    {
        LimitScope limit("512M");
        const auto usable = usableMemoryBytes();
        ASSERT_TRUE(usable.ok() && usable->has_value());
        EXPECT_EQ(**usable, std::uint64_t(512) << 20);
        EXPECT_FALSE(checkMemory(std::uint64_t(600) << 20, "a test", "nothing").ok());
        EXPECT_TRUE(checkMemory(std::uint64_t(500) << 20, "a test", "nothing").ok());
    }
    {
        LimitScope limit("999999G"); // a cap above what the system has changes nothing
        const auto usable = usableMemoryBytes();
        const auto available = availableMemoryBytes();
        ASSERT_TRUE(usable.ok() && usable->has_value() && available.has_value());
        EXPECT_LT(double(**usable), 2.0 * double(*available));
    }
    for (const char* ok : {"1", "2048K", "3m", "6G", "6g"}) {
        LimitScope limit(ok);
        EXPECT_TRUE(memoryLimitFromEnvironment().ok()) << ok;
    }
    for (const char* bad :
         {"", "G", "6T", "-1", "1.5G", "6 G", "99999999999999999999", "18014398509481984G"}) {
        LimitScope limit(bad);
        const auto r = memoryLimitFromEnvironment();
        ASSERT_FALSE(r.ok()) << bad;
        EXPECT_NE(r.error().find("BURNISH_MEMORY_LIMIT"), std::string::npos) << r.error();
        EXPECT_FALSE(checkMemory(1, "a test", "nothing").ok()) << "a bad limit is never ignored: " << bad;
    }
}

TEST(Memory, OnlyEightAndSixteenBitPngsAreDecodedByCore) {
    EXPECT_TRUE(decodedByCore("png", "uint8"));
    EXPECT_TRUE(decodedByCore("png", "uint16"));
    EXPECT_FALSE(decodedByCore("openexr", "half"));
    EXPECT_FALSE(decodedByCore("tga", "uint8"));
}

TEST(Memory, RefusalsGiveTheNeedAndWhatIsAvailableInOneLine) {
    EXPECT_TRUE(checkMemory(1000, std::uint64_t(2000), "x", "y").ok());
    EXPECT_TRUE(checkMemory(1000, std::nullopt, "x", "y").ok()); // unknown: not refused
    const Status refused =
        checkMemory(std::uint64_t(9.4e9), std::uint64_t(850e6), "evaluating a map", "less");
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error(),
              "evaluating a map needs about 9.4 GB of memory, and 850 MB are available (less)");
    EXPECT_EQ(formatBytes(std::uint64_t(12.34e9)), "12.3 GB");
    EXPECT_EQ(formatBytes(std::uint64_t(999e6)), "999 MB");
}

TEST(Memory, EnvironmentEstimatesMatchMeasuredPeaks) {
    struct Case {
        int faceSize;
        std::uint64_t inputTexels;
        double measuredMB;
    };
    // core/bench/command_memory.sh: courtyard.exr (1024×512) at each face size; the procedural studio.
    for (const Case& c : std::vector<Case>{{256, 1024 * 512, 180.6},
                                           {512, 1024 * 512, 241.2},
                                           {1024, 1024 * 512, 443.1},
                                           {2048, 1024 * 512, 1361.6},
                                           {512, 0, 222.1}})
        expectWithin(double(estimatedEnvironmentBytes(c.faceSize, c.inputTexels)), c.measuredMB * 1e6,
                     "env face " + std::to_string(c.faceSize));
    // A face size no machine holds is estimated, not overflowed.
    EXPECT_GT(estimatedEnvironmentBytes(16384, 0), std::uint64_t(60e9));
}

TEST(Memory, EvaluationEstimatesMatchMeasuredPeaks) {
    struct Case {
        int side;
        size_t lobeCounts;
        bool between, errorMaps, gloss;
        double measuredMB;
        bool exr = false;
    };
    // core/bench/command_memory.sh: trak-rust1 resized, every method, default mips and directions.
    for (const Case& c : std::vector<Case>{{512, 1, false, false, false, 97.9},
                                           {1024, 1, false, false, false, 354.8},
                                           {2048, 1, false, false, false, 1380.6},
                                           {1024, 1, true, false, false, 543.8},
                                           {1024, 4, false, false, false, 629.1},
                                           {1024, 4, true, false, false, 974.6},
                                           {1024, 1, false, true, false, 456.1},
                                           {1024, 1, false, false, true, 374.6},
                                           {512, 1, false, false, false, 148.8, true}}) {
        EvaluationMemoryInput in;
        in.mapTexels = std::uint64_t(c.side) * std::uint64_t(c.side);
        in.lobeCounts = c.lobeCounts;
        in.betweenTexels = c.between;
        in.errorMaps = c.errorMaps;
        in.gloss = c.gloss;
        in.openImageIo = c.exr;
        expectWithin(double(estimatedEvaluationBytes(in)), c.measuredMB * 1e6,
                     "evaluate " + std::to_string(c.side) + " K×" + std::to_string(c.lobeCounts) +
                         (c.between ? " between" : "") + (c.errorMaps ? " error maps" : "") +
                         (c.gloss ? " gloss" : "") + (c.exr ? " exr" : ""));
    }
}

} // namespace
} // namespace burnish
