// Atomic file output (atomic_file.h): write and replace, refuse to overwrite, clear errors, and no
// temporary file left behind whatever happens.
#include <burnish/core/util/files.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>

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

TEST_F(AtomicFile, CommitTemporary) {
    const fs::path target = m_dir / "c.txt";
    const fs::path tmp = temporaryPathFor(target);
    EXPECT_EQ(tmp.parent_path(), target.parent_path()); // same folder, so rename(2) is atomic
    EXPECT_NE(temporaryPathFor(target), tmp);           // unique per call
    std::ofstream(tmp) << "payload";
    ASSERT_TRUE(commitTemporary(tmp, target).ok());
    EXPECT_EQ(slurp(target), "payload");
    // Refused: the temporary is removed, the target kept.
    const fs::path tmp2 = temporaryPathFor(target);
    std::ofstream(tmp2) << "other";
    EXPECT_FALSE(commitTemporary(tmp2, target, Overwrite::Refuse).ok());
    EXPECT_EQ(slurp(target), "payload");
    EXPECT_EQ(listing(), std::set<std::string>{"c.txt"});
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
