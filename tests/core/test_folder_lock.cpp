// One writer at a time per output folder (util/files.h FolderLock, held by FileSet and by a bake's export):
// a second writer waits or gives up in one line naming the holder, the lock file is gone once the writer is
// done, and two writers of different sets into one folder at once always leave one whole set.
#include <burnish/core/util/files.h>

#include "temp_dir.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace burnish {
namespace {

namespace fs = std::filesystem;

std::string readText(const fs::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

std::set<std::string> listing(const fs::path& dir) {
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir))
        names.insert(e.path().filename().string());
    return names;
}

TEST(FolderLock, ASecondWriterWaitsOrGivesUpNamingTheHolder) {
    test::TempDir dir;
    {
        auto first = FolderLock::acquire(dir.path());
        ASSERT_TRUE(first) << first.error();
        EXPECT_TRUE(first->held());
        EXPECT_TRUE(fs::exists(dir.path() / std::string(kWriterLockName)));
        const auto start = std::chrono::steady_clock::now();
        auto second = FolderLock::acquire(dir.path(), 0.2);
        const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        ASSERT_FALSE(second);
        EXPECT_GE(waited, 0.2);
        EXPECT_NE(second.error().find("being written by another Burnish process (pid " +
                                      std::to_string(::getpid()) + ")"),
                  std::string::npos)
            << second.error();
        EXPECT_EQ(second.error().find('\n'), std::string::npos);
        // A waiter gets it as soon as the holder lets go.
        std::thread release([lock = std::move(first).value()]() mutable {
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
            FolderLock gone = std::move(lock);
        });
        auto third = FolderLock::acquire(dir.path(), 10.0);
        release.join();
        ASSERT_TRUE(third) << third.error();
        EXPECT_TRUE(third->held());
    }
    // Nothing is left once the writers are done.
    EXPECT_TRUE(listing(dir.path()).empty());
    // A folder that does not exist is not locked; the writer's own checks report it.
    auto missing = FolderLock::acquire(dir.path() / "missing");
    ASSERT_TRUE(missing);
    EXPECT_FALSE(missing->held());
}

// Two writers of different sets (same index name, partly the same file names, as two bakes of different maps
// with one stem) into one folder at once, each slowed while it stages: the second's FileSet::begin returns
// only once the first has committed (without the lock both stage at once and their commits may interleave),
// and every time the folder holds one whole set — the index and exactly its files, each with that set's
// content — and no lock file.
TEST(FolderLock, TwoWritersAtOnceAlwaysLeaveOneWholeSet) {
    test::TempDir dir;
    const std::map<std::string, std::vector<std::string>> sets{{"A", {"a.txt", "b.txt", "c.txt"}},
                                                               {"B", {"a.txt", "b.txt", "d.txt", "e.txt"}}};
    for (int round = 0; round < 12; ++round) {
        std::atomic<int> ready{0}, begunCount{0}, committed{0};
        std::atomic<bool> secondWaited{false};
        auto writer = [&](const std::string& tag) {
            ++ready;
            while (ready.load() < 2)
                std::this_thread::yield(); // a barrier: both start together
            auto begun = FileSet::begin(dir.path());
            ASSERT_TRUE(begun) << begun.error();
            if (++begunCount == 2) secondWaited = committed.load() == 1;
            FileSet& set = begun.value();
            std::string index;
            for (const std::string& name : sets.at(tag)) {
                ASSERT_TRUE(set.addBytes(name, tag + " " + name));
                std::this_thread::sleep_for(std::chrono::milliseconds(5)); // overlap the other writer
                index += name + "\n";
            }
            ASSERT_TRUE(set.addBytes("index.txt", index));
            // The previous set's files this one does not write go with it, as a bake's do.
            std::vector<std::string> obsolete;
            for (const std::string old : {"c.txt", "d.txt", "e.txt"}) // NOLINT(performance-for-range-copy)
                if (std::find(sets.at(tag).begin(), sets.at(tag).end(), old) == sets.at(tag).end())
                    obsolete.push_back(old);
            ASSERT_TRUE(set.commit("index.txt", obsolete, Overwrite::Allow));
            ++committed;
        };
        std::thread a(writer, "A"), b(writer, "B");
        a.join();
        b.join();
        EXPECT_TRUE(secondWaited) << "round " << round << ": both writers were in the folder at once";
        const std::string index = readText(dir.path() / "index.txt");
        const std::string tag = index.find("e.txt") != std::string::npos ? "B" : "A";
        std::set<std::string> expected{"index.txt"};
        for (const std::string& name : sets.at(tag)) {
            expected.insert(name);
            EXPECT_EQ(readText(dir.path() / name), tag + " " + name) << "round " << round;
        }
        ASSERT_EQ(listing(dir.path()), expected) << "round " << round << ": a mixed or partial set";
    }
}

} // namespace
} // namespace burnish
