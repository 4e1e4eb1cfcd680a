// Atomic file output (atomic_file.h): write and replace, refuse to overwrite, clear errors, and no
// temporary file left behind whatever happens.
#include <burnish/core/util/files.h>

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

namespace burnish {
namespace {

namespace fs = std::filesystem;

// A fresh, empty folder per test, removed with everything in it at the end.
class AtomicFile : public ::testing::Test {
protected:
    void SetUp() override {
        static std::atomic<int> counter{0};
        const auto stamp = std::chrono::steady_clock::now().time_since_epoch().count();
        m_dir = fs::temp_directory_path() / ("burnish-atomic-" + std::to_string(::getpid()) + "-" +
                                             std::to_string(stamp) + "-" + std::to_string(counter++));
        ASSERT_TRUE(fs::create_directory(m_dir)) << m_dir;
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(m_dir, ec);
    }

    // The names in the folder, to show that nothing but the expected files is there.
    std::set<std::string> listing() const {
        std::set<std::string> names;
        for (const auto& entry : fs::directory_iterator(m_dir))
            names.insert(entry.path().filename().string());
        return names;
    }

    static std::string slurp(const fs::path& path) {
        std::ifstream in(path, std::ios::binary);
        std::string bytes(static_cast<size_t>(fs::file_size(path)), '\0');
        in.read(bytes.data(), static_cast<std::streamsize>(bytes.size()));
        return bytes;
    }

    fs::path m_dir;
};

TEST_F(AtomicFile, WritesAndReplaces) {
    const fs::path target = m_dir / "out.txt";
    ASSERT_TRUE(writeFileAtomic(target, "first").ok());
    EXPECT_EQ(slurp(target), "first");
    // Binary content with NUL bytes survives unchanged.
    const std::string binary("a\0b\n\xff", 5);
    const Status second = writeFileAtomic(target, binary);
    ASSERT_TRUE(second.ok()) << second.error();
    EXPECT_EQ(slurp(target), binary);
    EXPECT_EQ(listing(), std::set<std::string>{"out.txt"});
    // An empty payload is a valid (empty) file.
    ASSERT_TRUE(writeFileAtomic(target, "").ok());
    EXPECT_EQ(fs::file_size(target), 0u);
    EXPECT_EQ(listing(), std::set<std::string>{"out.txt"});
}

TEST_F(AtomicFile, RefuseKeepsTheExistingFile) {
    const fs::path target = m_dir / "keep.txt";
    ASSERT_TRUE(writeFileAtomic(target, "original", Overwrite::Refuse).ok()); // new file: allowed
    const Status s = writeFileAtomic(target, "replacement", Overwrite::Refuse);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.error().find(target.string()), std::string::npos) << s.error();
    EXPECT_NE(s.error().find("overwrite"), std::string::npos) << s.error();
    EXPECT_EQ(slurp(target), "original");
    EXPECT_EQ(listing(), std::set<std::string>{"keep.txt"});
}

TEST_F(AtomicFile, MissingFolderIsNamed) {
    const fs::path missing = m_dir / "no-such-folder";
    const Status s = writeFileAtomic(missing / "out.txt", "data");
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.error().find(missing.string()), std::string::npos) << s.error();
    EXPECT_FALSE(fs::exists(missing));
    EXPECT_TRUE(listing().empty());
}

TEST_F(AtomicFile, FailedRenameLeavesNoTemporary) {
    // The target is an existing non-empty folder: the temporary is written, the rename fails.
    const fs::path target = m_dir / "occupied";
    fs::create_directory(target);
    std::ofstream(target / "inside.txt") << "x";
    const Status s = writeFileAtomic(target, "data");
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.error().find(target.string()), std::string::npos) << s.error();
    EXPECT_EQ(listing(), std::set<std::string>{"occupied"});
    EXPECT_EQ(slurp(target / "inside.txt"), "x");
}

TEST_F(AtomicFile, StagingFolderIsPrivateAndRemoved) {
    fs::path inside;
    {
        auto staging = StagingFolder::create(m_dir);
        ASSERT_TRUE(staging) << staging.error();
        inside = staging->path();
        EXPECT_TRUE(fs::equivalent(inside.parent_path(), m_dir)); // same file system: atomic rename
        EXPECT_EQ(inside.filename().string().rfind(kStagingPrefix, 0), 0u) << inside;
        // Only its owner may create names in it.
        EXPECT_EQ(fs::status(inside).permissions() & fs::perms::all, fs::perms::owner_all);
        const fs::path staged = staging.value().fileFor(m_dir / "a.exr");
        EXPECT_EQ(staged.parent_path(), inside);
        EXPECT_EQ(staged.extension(), ".exr");
        EXPECT_NE(staging.value().fileFor(m_dir / "a.exr"), staged); // unique per call
        ASSERT_TRUE(writeNewFile(staged, "x").ok());
        EXPECT_FALSE(writeNewFile(staged, "y").ok()); // exclusive creation
        // A live folder is in use: recovery leaves it alone.
        const StagingRecovery r = recoverStaging(m_dir);
        EXPECT_EQ(r.foldersRemoved + r.commitsFinished, 0);
        EXPECT_TRUE(fs::exists(staged));
    }
    EXPECT_FALSE(fs::exists(inside));
    EXPECT_TRUE(listing().empty());
}

TEST_F(AtomicFile, InstallFileRefuseKeepsTheTarget) {
    auto staging = StagingFolder::create(m_dir);
    ASSERT_TRUE(staging) << staging.error();
    const fs::path target = m_dir / "c.txt";
    std::ofstream(target) << "payload";
    const fs::path staged = staging.value().fileFor(target);
    ASSERT_TRUE(writeNewFile(staged, "other").ok());
    const Status s = installFile(staged, target, Overwrite::Refuse);
    EXPECT_FALSE(s.ok());
    EXPECT_NE(s.error().find("refusing to overwrite"), std::string::npos) << s.error();
    EXPECT_EQ(slurp(target), "payload");
    ASSERT_TRUE(installFile(staged, target).ok());
    EXPECT_EQ(slurp(target), "other");
}

// Links planted at every name the old scheme ("<target>.tmp-<pid>-<n>") would have used, and at
// the target itself: the file outside the folder stays as it was and the output is correct.
TEST_F(AtomicFile, PlantedLinksAreNotFollowed) {
    const fs::path outsideDir = m_dir / "outside";
    const fs::path shared = m_dir / "shared";
    fs::create_directory(outsideDir);
    fs::create_directory(shared);
    const fs::path victim = outsideDir / "victim.txt";
    std::ofstream(victim) << "precious";
    const fs::path target = shared / "out.txt";
    for (int n = 0; n < 64; ++n)
        fs::create_symlink(victim,
                           shared / ("out.txt.tmp-" + std::to_string(::getpid()) + "-" + std::to_string(n)));
    fs::create_symlink(victim, target);
    ASSERT_TRUE(writeFileAtomic(target, "fresh").ok());
    EXPECT_EQ(slurp(victim), "precious");
    EXPECT_FALSE(fs::is_symlink(target)); // the link itself was replaced, not followed
    EXPECT_EQ(slurp(target), "fresh");
}

TEST_F(AtomicFile, WriteAtomicWithALibraryWriter) {
    const fs::path target = m_dir / "lib.bin";
    fs::path seen;
    const Status s = writeAtomicWith(target, [&](const fs::path& staged) -> Status {
        seen = staged;
        std::ofstream(staged) << "library bytes";
        return {};
    });
    ASSERT_TRUE(s.ok()) << s.error();
    EXPECT_NE(seen.parent_path(), m_dir); // written inside the private folder
    EXPECT_EQ(slurp(target), "library bytes");
    EXPECT_EQ(listing(), std::set<std::string>{"lib.bin"});
    // A writer's error comes back as it is, and nothing is left.
    const Status failed =
        writeAtomicWith(m_dir / "no.bin", [](const fs::path&) -> Status { return Error{"boom"}; });
    EXPECT_EQ(failed.error(), "boom");
    EXPECT_EQ(listing(), std::set<std::string>{"lib.bin"});
}

// A set: the old index is removed first and the new one renamed last; obsolete files of the old
// set go, names outside the folder are never touched.
TEST_F(AtomicFile, CommitSetReplacesTheWholeSet) {
    std::ofstream(m_dir / "index.json") << "old index";
    std::ofstream(m_dir / "a.txt") << "old a";
    std::ofstream(m_dir / "old-only.txt") << "old only";
    std::ofstream(m_dir / "keep.txt") << "not in any set";
    std::ofstream(m_dir / "outside.txt") << "outside";
    fs::create_directory(m_dir / "sub");
    auto staging = StagingFolder::create(m_dir / "sub");
    ASSERT_TRUE(staging) << staging.error();
    const fs::path sub = m_dir / "sub";
    std::ofstream(sub / "index.json") << "old index";
    std::ofstream(sub / "a.txt") << "old a";
    std::ofstream(sub / "old-only.txt") << "old only";
    std::vector<StagedFile> files;
    for (const char* name : {"a.txt", "b.txt", "index.json"}) {
        const fs::path staged = staging.value().fileFor(sub / name);
        ASSERT_TRUE(writeNewFile(staged, std::string("new ") + name).ok());
        files.push_back({staged, sub / name});
    }
    SetCommit commit;
    commit.index = sub / "index.json";
    commit.obsolete = {sub / "old-only.txt", sub / "a.txt", sub / ".." / "outside.txt", sub / "missing.txt"};
    std::vector<int> steps;
    setCommitStepHookForTesting([&](int step) {
        steps.push_back(step);
        // While the files move, the folder holds no index: a reader sees an incomplete set.
        if (step > 1 && step < 7) {
            EXPECT_FALSE(fs::exists(sub / "index.json")) << step;
        }
    });
    const Status s = commitSet(staging.value(), files, commit);
    setCommitStepHookForTesting(nullptr);
    ASSERT_TRUE(s.ok()) << s.error();
    // journal, old index removed, a, b, old-only and missing removed, index.
    EXPECT_EQ(steps, (std::vector<int>{1, 2, 3, 4, 5, 6, 7}));
    EXPECT_EQ(slurp(sub / "a.txt"), "new a.txt");
    EXPECT_EQ(slurp(sub / "b.txt"), "new b.txt");
    EXPECT_EQ(slurp(sub / "index.json"), "new index.json");
    EXPECT_FALSE(fs::exists(sub / "old-only.txt"));
    EXPECT_EQ(slurp(m_dir / "outside.txt"), "outside");
    EXPECT_EQ(slurp(m_dir / "old-only.txt"), "old only");
}

TEST_F(AtomicFile, FileSetStagesFilesInParallelInTheGivenOrder) {
    auto begun = FileSet::begin(m_dir);
    ASSERT_TRUE(begun) << begun.error();
    FileSet& set = begun.value();
    ASSERT_TRUE(set.addBytes("first.txt", "first").ok());
    std::vector<std::string> names;
    for (int i = 0; i < 16; ++i)
        names.push_back("f" + std::to_string(i) + ".txt");
    const Status s = set.addParallel(names, [&](size_t i, const fs::path& staged) {
        return writeNewFile(staged, names[i] + " bytes", m_dir / names[i]);
    });
    ASSERT_TRUE(s.ok()) << s.error();
    std::vector<std::string> expected{"first.txt"};
    expected.insert(expected.end(), names.begin(), names.end());
    EXPECT_EQ(set.names(), expected);
    // A failed writer: its error (the first in order), and none of the batch is listed.
    const Status failed =
        set.addParallel({"g0.txt", "g1.txt", "g2.txt"}, [&](size_t i, const fs::path& staged) {
            return i == 0 ? writeNewFile(staged, "g0", m_dir / "g0.txt")
                          : Status(Error{"writer " + std::to_string(i)});
        });
    ASSERT_FALSE(failed.ok());
    EXPECT_EQ(failed.error(), "writer 1");
    EXPECT_EQ(set.names(), expected);
    EXPECT_FALSE(set.addParallel({"../escape.txt"}, [](size_t, const fs::path&) { return Status{}; }).ok());
    ASSERT_TRUE(set.commit("", {}, Overwrite::Allow).ok());
    for (const auto& name : names)
        EXPECT_EQ(slurp(m_dir / name), name + " bytes");
    EXPECT_FALSE(fs::exists(m_dir / "g0.txt")); // staged by the failed batch, never listed
}

TEST_F(AtomicFile, RecoveryRemovesStaleTemporariesOfDeadProcessesOnly) {
    // A process that is gone: a child that has exited and been reaped.
    const pid_t child = ::fork();
    if (child == 0) ::_exit(0);
    int status = 0;
    ::waitpid(child, &status, 0);
    const std::string dead = "t.png.tmp-" + std::to_string(child) + "-3";
    const std::string alive = "t.png.tmp-" + std::to_string(::getpid()) + "-1";
    std::ofstream(m_dir / dead) << "x";
    std::ofstream(m_dir / alive) << "x";
    std::ofstream(m_dir / "photo.tmp-holiday-1") << "not ours";
    // An abandoned staging folder (no journal, no lock).
    fs::create_directory(m_dir / (std::string(kStagingPrefix) + "abcdef"));
    std::ofstream(m_dir / (std::string(kStagingPrefix) + "abcdef") / "0-t.png") << "partial";
    const StagingRecovery r = recoverStaging(m_dir);
    EXPECT_EQ(r.temporariesRemoved, 1);
    EXPECT_EQ(r.foldersRemoved, 1);
    EXPECT_EQ(r.commitsFinished, 0);
    EXPECT_EQ(r.notes.size(), 2u);
    EXPECT_EQ(listing(), (std::set<std::string>{alive, "photo.tmp-holiday-1"}));
}

TEST_F(AtomicFile, ReadFile) {
    const fs::path target = m_dir / "r.bin";
    const std::string bytes("x\0y", 3);
    ASSERT_TRUE(writeFileAtomic(target, bytes).ok());
    const auto r = readFile(target);
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_EQ(*r, bytes);

    const fs::path missing = m_dir / "missing.txt";
    const auto m = readFile(missing);
    EXPECT_FALSE(m.ok());
    EXPECT_NE(m.error().find(missing.string()), std::string::npos) << m.error();
    EXPECT_NE(m.error().find("does not exist"), std::string::npos) << m.error();

    const auto d = readFile(m_dir);
    EXPECT_FALSE(d.ok());
    EXPECT_NE(d.error().find(m_dir.string()), std::string::npos) << d.error();
    EXPECT_NE(d.error().find("folder"), std::string::npos) << d.error();
}

} // namespace
} // namespace burnish
