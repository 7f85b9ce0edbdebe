// SPDX-License-Identifier: MIT
/// @file
/// @brief Atomic, checked writes and import limits (lucent/core/FileIO.h): a write that fails
/// late (in the last buffer, at close) keeps the old file and leaves no temporary; stale
/// temporaries of killed runs are removed on the next write; non-regular and oversized inputs
/// are rejected. Readers isolated in a child process (lucent/core/Isolate.h).

#include <lucent/core/Error.h>
#include <lucent/core/FileIO.h>
#include <lucent/core/Image.h>
#include <lucent/core/Isolate.h>

#include <gtest/gtest.h>

#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include <sys/mount.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace lucent;
namespace fs = std::filesystem;

namespace {

fs::path testDir(const std::string& name) {
    const fs::path dir = fs::path(LUCENT_TEST_OUTPUT_DIR) / "fileio" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

std::string readAll(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
}

/// Names in `dir` other than `keep`.
std::vector<std::string> othersIn(const fs::path& dir, const std::string& keep) {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(dir))
        if (e.path().filename() != keep)
            out.push_back(e.path().filename().string());
    return out;
}

/// A noisy image whose PNG does not compress to nothing (deterministic).
ImageRgb noiseImage(int w, int h) {
    ImageRgb img(w, h);
    uint32_t s = 12345;
    for (Rgb& p : img.pixels())
        for (int c = 0; c < 3; ++c) {
            s = s * 1664525u + 1013904223u;
            p[c] = float(s >> 8) / float(1u << 24);
        }
    return img;
}

/// Limits the size of files this process writes (RLIMIT_FSIZE) for its lifetime: a write past
/// the limit fails with EFBIG, like a full disk, without needing root or a small file system.
class FileSizeLimit {
public:
    explicit FileSizeLimit(rlim_t bytes) {
        getrlimit(RLIMIT_FSIZE, &m_old);
        m_oldHandler = std::signal(SIGXFSZ, SIG_IGN);  // fail the write instead of the process
        rlimit lim = m_old;
        lim.rlim_cur = bytes;
        EXPECT_EQ(setrlimit(RLIMIT_FSIZE, &lim), 0);
    }
    ~FileSizeLimit() {
        setrlimit(RLIMIT_FSIZE, &m_old);
        std::signal(SIGXFSZ, m_oldHandler);
    }

private:
    rlimit m_old{};
    void (*m_oldHandler)(int) = nullptr;
};

/// Writes with `write` while files are limited to `limit` bytes; expects an IoError, the old
/// file unchanged and no temporary left beside it.
template <typename WriteFn>
void expectFailedWriteKeepsOldFile(const fs::path& dir, const std::string& name, rlim_t limit,
                                   WriteFn write) {
    const fs::path target = dir / name;
    {
        std::ofstream f(target, std::ios::binary);
        f << "the previous good file";
    }
    {
        FileSizeLimit guard(limit);
        EXPECT_THROW(write(target.string()), IoError) << name;
    }
    EXPECT_EQ(readAll(target), "the previous good file") << name;
    EXPECT_TRUE(othersIn(dir, name).empty()) << name << ": a temporary was left behind";
}

}  // namespace

TEST(FileIO, WriteFailingInTheLastBufferKeepsTheOldPng) {
    // Regression (issue 18 §2): on a full disk the stdio buffer flushed by fclose failed, the
    // error was discarded and the truncated temporary replaced the good file. The limit is one
    // byte short of the PNG, so only the very last write (at close) fails.
    const fs::path dir = testDir("png");
    const ImageRgb img = noiseImage(64, 48);
    writePng(img, (dir / "probe.png").string());
    const uintmax_t size = fs::file_size(dir / "probe.png");
    ASSERT_GT(size % 4096, 1u) << "the last stdio buffer must hold more than one byte";
    fs::remove(dir / "probe.png");
    expectFailedWriteKeepsOldFile(dir, "r.png", rlim_t(size - 1),
                                  [&](const std::string& p) { writePng(img, p); });
}

TEST(FileIO, WriteFailingInTheLastBufferKeepsTheOldExr) {
    // OpenEXR writes its line-offset table from the OutputFile destructor, which swallows
    // errors: the failure must still be seen.
    const fs::path dir = testDir("exr");
    const ImageRgb img = noiseImage(32, 16);
    writeExr(img, (dir / "probe.exr").string());
    const uintmax_t size = fs::file_size(dir / "probe.exr");
    fs::remove(dir / "probe.exr");
    for (rlim_t limit : {rlim_t(0), rlim_t(size / 2), rlim_t(size - 1)})
        expectFailedWriteKeepsOldFile(dir, "r.exr", limit,
                                      [&](const std::string& p) { writeExr(img, p); });
}

TEST(FileIO, FailedStreamedWriteKeepsTheOldFile) {
    const fs::path dir = testDir("stream");
    const std::string bytes(100000, 'x');
    for (rlim_t limit : {rlim_t(0), rlim_t(4096), rlim_t(99999)})
        expectFailedWriteKeepsOldFile(dir, "data.bin", limit,
                                      [&](const std::string& p) { writeFileAtomically(p, bytes); });
    // A writer that throws half-way: same guarantee.
    const fs::path target = dir / "data.bin";
    EXPECT_THROW(writeStreamAtomically(target.string(),
                                       [](FileSink& out) {
                                           out.write("partial");
                                           LUCENT_THROW(IoError, "writer gave up");
                                       }),
                 IoError);
    EXPECT_EQ(readAll(target), "the previous good file");
    EXPECT_TRUE(othersIn(dir, "data.bin").empty());
}

TEST(FileIO, WriteIntoAMissingOrReadOnlyFolderFailsCleanly) {
    const fs::path dir = testDir("folders");
    const fs::path missing = dir / "no-such-dir" / "x.png";
    try {
        writePng(noiseImage(4, 4), missing.string());
        ADD_FAILURE() << "no error for a missing folder";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "no-such-dir"));
    const fs::path ro = dir / "read-only";
    fs::create_directories(ro);
    writeFileAtomically((ro / "kept.txt").string(), std::string_view("old"));
    // Root ignores folder permissions: make the folder a read-only bind mount instead.
    const bool root = geteuid() == 0;
    if (root) {
        if (mount(ro.c_str(), ro.c_str(), nullptr, MS_BIND, nullptr) != 0)
            GTEST_SKIP() << "running as root without mount rights: no read-only folder";
        if (mount(nullptr, ro.c_str(), nullptr, MS_REMOUNT | MS_BIND | MS_RDONLY, nullptr) != 0) {
            umount2(ro.c_str(), 0);
            GTEST_SKIP() << "cannot remount read-only";
        }
    } else {
        fs::permissions(ro, fs::perms::owner_read | fs::perms::owner_exec);
    }
    EXPECT_THROW(writeFileAtomically((ro / "kept.txt").string(), std::string_view("new")), IoError);
    if (root)
        umount2(ro.c_str(), 0);
    else
        fs::permissions(ro, fs::perms::owner_all);
    EXPECT_EQ(readAll(ro / "kept.txt"), "old");
}

TEST(FileIO, StaleTemporariesOfKilledWritesAreRemovedOnTheNextWrite) {
    // Regression (issue 18 §2): a SIGKILLed export left `<target>.tmp-*` behind for good.
    const fs::path dir = testDir("stale");
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0)
        _exit(0);
    ASSERT_EQ(waitpid(child, nullptr, 0), child);  // a process id that no longer runs
    const std::string deadPid = std::to_string(long(child));
    const auto touch = [&](const std::string& name) {
        std::ofstream(dir / name) << "";
        return dir / name;
    };
    const fs::path deadNew = touch("r.png.tmp-" + deadPid + "-0123abcd.png");
    const fs::path legacy = touch("r.png.tmp-3735928559");  // earlier versions' pattern
    fs::last_write_time(legacy, fs::file_time_type::clock::now() - std::chrono::hours(1));
    // Kept: a live writer's temporary (pid 1 always runs), a recent legacy one, other targets'
    // temporaries and names that merely look similar.
    const fs::path live = touch("r.png.tmp-1-0123abcd.png");
    const fs::path recentLegacy = touch("r.png.tmp-42");
    const fs::path otherTarget = touch("q.png.tmp-" + deadPid + "-0123abcd.png");
    const fs::path lookalike = touch("r.png.tmp-notours");
    const fs::path userFile = touch("r.png.tmp-" + deadPid + "-0123abcd.png.bak");

    writePng(noiseImage(4, 4), (dir / "r.png").string());
    EXPECT_FALSE(fs::exists(deadNew));
    EXPECT_FALSE(fs::exists(legacy));
    for (const fs::path& p : {live, recentLegacy, otherTarget, lookalike, userFile})
        EXPECT_TRUE(fs::exists(p)) << p;
}

TEST(FileIO, KilledWriterLeavesTheOldFileAndItsTemporaryIsCleanedUp) {
    const fs::path dir = testDir("killed");
    const fs::path target = dir / "out.vdb";
    writeFileAtomically(target.string(), std::string_view("good"));
    const pid_t child = fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
        try {
            writeStreamAtomically(target.string(), [](FileSink& out) {
                out.write(std::string(1000, 'z'));
                out.flush();
                raise(SIGKILL);
            });
        } catch (...) {
        }
        _exit(1);
    }
    int status = 0;
    ASSERT_EQ(waitpid(child, &status, 0), child);
    ASSERT_TRUE(WIFSIGNALED(status));
    EXPECT_EQ(readAll(target), "good");
    EXPECT_EQ(othersIn(dir, "out.vdb").size(), 1u);  // the killed run's temporary
    writeFileAtomically(target.string(), std::string_view("next"));
    EXPECT_EQ(readAll(target), "next");
    EXPECT_TRUE(othersIn(dir, "out.vdb").empty());
}

TEST(FileIO, InputsThatAreNotBoundedRegularFilesAreRejected) {
    EXPECT_THROW(checkInputFile("/dev/zero", "scene file"), IoError);
    EXPECT_THROW(checkInputFile(LUCENT_TEST_OUTPUT_DIR, "scene file"), IoError);
    EXPECT_THROW(checkInputFile("/no/such/file", "scene file"), IoError);
    const fs::path dir = testDir("limits");
    writeFileAtomically((dir / "big.txt").string(), std::string(5000, 'a'));
    EXPECT_EQ(checkInputFile((dir / "big.txt").string(), "text"), 5000u);
    ImportLimits small = importLimits();
    small.maxFileBytes = 4096;
    {
        ScopedImportLimits scoped(small);
        try {
            readInputFile((dir / "big.txt").string(), "text");
            ADD_FAILURE() << "no error over the limit";
        } catch (const IoError& e) {
            EXPECT_NE(std::string(e.what()).find("import limit"), std::string::npos) << e.what();
        }
    }
    EXPECT_EQ(readInputFile((dir / "big.txt").string(), "text").size(), 5000u);
    EXPECT_THROW(readInputFile((dir / "big.txt").string(), "text", /*maxBytes=*/100), IoError);
    EXPECT_THROW(checkElementCount(importLimits().maxElements + 1, "mesh file", "m.off", "faces"),
                 IoError);
}

TEST(FileIO, ImageReadersRejectFilesOverTheDecodedLimit) {
    const fs::path dir = testDir("decoded");
    writePng(noiseImage(64, 64), (dir / "a.png").string());
    writeExr(noiseImage(64, 64), (dir / "a.exr").string());
    ImportLimits small = importLimits();
    small.maxDecodedBytes = 64 * 64 * sizeof(Rgb) - 1;
    ScopedImportLimits scoped(small);
    EXPECT_THROW(readPng((dir / "a.png").string()), IoError);
    EXPECT_THROW(readExr((dir / "a.exr").string()), IoError);
}

TEST(Isolate, ResultsErrorsCrashesAndRunawaysOfTheChild) {
    EXPECT_EQ(runIsolated("echo", [] { return std::string("a\0b", 3); }), std::string("a\0b", 3));
    try {
        runIsolated("reader", []() -> std::string { LUCENT_THROW(IoError, "bad header"); });
        ADD_FAILURE() << "no error";
    } catch (const IoError& e) {
        EXPECT_STREQ(e.what(), "reader: bad header");
    }
    try {
        runIsolated("crasher", []() -> std::string {
            raise(SIGSEGV);
            return {};
        });
        ADD_FAILURE() << "no error";
    } catch (const IoError& e) {
        // The child's own signal, in every build: under AddressSanitizer too, whose crash
        // handler would otherwise print a report and end the child with SIGABRT.
        const std::string expected = std::string("crasher: crashed (") + strsignal(SIGSEGV) + ")";
        EXPECT_NE(std::string(e.what()).find(expected), std::string::npos) << e.what();
    }
    ImportLimits tight = importLimits();
    tight.maxReaderCpuSeconds = 1;
    tight.maxDecodedBytes = uint64_t(64) << 20;
    ScopedImportLimits scoped(tight);
    try {
        runIsolated("spinner", []() -> std::string {
            volatile uint64_t n = 0;
            for (;;)
                n = n + 1;
        });
        ADD_FAILURE() << "no error";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("CPU time limit of 1 s"), std::string::npos)
            << e.what();
    }
    EXPECT_THROW(runIsolated("chatty", [] { return std::string(65 << 20, 'x'); }), IoError);
// AddressSanitizer and ThreadSanitizer need the whole address space (Isolate.cpp).
#if !defined(__SANITIZE_ADDRESS__) && !defined(__SANITIZE_THREAD__)
    try {
        runIsolated("glutton", [] {
            std::vector<char> big(size_t(1) << 30, 1);  // 1 GiB over a 64 MiB limit
            return std::string(1, big[12345]);
        });
        ADD_FAILURE() << "no error";
    } catch (const IoError& e) {
        EXPECT_NE(std::string(e.what()).find("out of memory"), std::string::npos) << e.what();
    }
#endif
}
