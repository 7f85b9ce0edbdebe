// SPDX-License-Identifier: MIT
/// @file
/// @brief Import limits and atomic, checked file writes (see lucent/core/FileIO.h).

#include <lucent/core/FileIO.h>

#include <lucent/core/Error.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>

#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

namespace lucent {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------- input

namespace {

std::mutex& limitsMutex() {
    static std::mutex m;
    return m;
}
ImportLimits& limitsStorage() {
    static ImportLimits limits;
    return limits;
}

std::string systemError(int err) {
    return std::strerror(err);
}

}  // namespace

ImportLimits importLimits() {
    const std::lock_guard<std::mutex> lock(limitsMutex());
    return limitsStorage();
}

void setImportLimits(const ImportLimits& limits) {
    LUCENT_CHECK(limits.maxFileBytes > 0 && limits.maxElements > 0 && limits.maxDecodedBytes > 0 &&
                     limits.maxReaderCpuSeconds > 0,
                 "import limits must be > 0");
    const std::lock_guard<std::mutex> lock(limitsMutex());
    limitsStorage() = limits;
}

ScopedImportLimits::ScopedImportLimits(const ImportLimits& limits) : m_previous(importLimits()) {
    setImportLimits(limits);
}

ScopedImportLimits::~ScopedImportLimits() {
    setImportLimits(m_previous);
}

uint64_t checkInputFile(const std::string& path, const std::string& what) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        const int err = errno;
        if (err == ENOENT || err == ENOTDIR)
            LUCENT_THROW(IoError, what, " '", path, "' does not exist");
        LUCENT_THROW(IoError, "cannot read ", what, " '", path, "': ", systemError(err));
    }
    // A device (/dev/zero), FIFO or socket can deliver bytes without end, and a folder none.
    if (!S_ISREG(st.st_mode))
        LUCENT_THROW(IoError, what, " '", path,
                     "' is not a regular file (a folder, device or pipe cannot be imported)");
    const uint64_t size = uint64_t(st.st_size);
    const uint64_t limit = importLimits().maxFileBytes;
    if (size > limit)
        LUCENT_THROW(IoError, what, " '", path, "' is ", size,
                     " bytes, more than the import limit of ", limit, " bytes");
    return size;
}

std::string readInputFile(const std::string& path, const std::string& what, uint64_t maxBytes) {
    const uint64_t size = checkInputFile(path, what);
    if (maxBytes > 0 && size > maxBytes)
        LUCENT_THROW(IoError, what, " '", path, "' is ", size, " bytes, more than the ", maxBytes,
                     " bytes accepted for this kind of file");
    std::ifstream in(path, std::ios::binary);
    if (!in)
        LUCENT_THROW(IoError, "cannot open ", what, " '", path, "' for reading");
    std::string bytes(size_t(size), '\0');
    in.read(bytes.data(), std::streamsize(size));
    if (uint64_t(in.gcount()) != size)
        LUCENT_THROW(IoError, "cannot read ", what, " '", path, "' (changed while reading?)");
    return bytes;
}

void checkElementCount(uint64_t count, const std::string& what, const std::string& path,
                       const char* noun) {
    const uint64_t limit = importLimits().maxElements;
    if (count > limit)
        LUCENT_THROW(IoError, what, " '", path, "' claims ", count, " ", noun,
                     ", more than the import limit of ", limit);
}

// --------------------------------------------------------------------------------- output

namespace {

constexpr size_t SINK_BUFFER_BYTES = size_t(1) << 18;

/// Writes all `n` bytes (retrying short writes and EINTR); 0 or the errno of the failure.
int writeAll(int fd, const char* p, size_t n) noexcept {
    while (n > 0) {
        const ssize_t w = ::write(fd, p, n);
        if (w < 0) {
            if (errno == EINTR)
                continue;
            return errno;
        }
        if (w == 0)
            return EIO;
        p += w;
        n -= size_t(w);
    }
    return 0;
}

/// fsync of the folder holding a renamed file, so that the rename itself survives a crash.
/// Folders that cannot be synced (EINVAL: not supported by the file system) are skipped.
void syncFolder(const std::string& path) {
    fs::path dir = fs::path(path).parent_path();
    if (dir.empty())
        dir = ".";
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0)
        return;  // the file is in place; a folder we cannot open cannot be synced either
    const int rc = ::fsync(fd);
    const int err = errno;
    ::close(fd);
    if (rc != 0 && err != EINVAL && err != ENOTSUP)
        LUCENT_THROW(IoError, "'", path,
                     "' was written but its folder could not be synced: ", systemError(err));
}

bool allDigits(std::string_view s) {
    return !s.empty() && s.find_first_not_of("0123456789") == std::string_view::npos;
}

bool isProcessGone(long pid) {
    if (pid <= 0 || pid == long(::getpid()))
        return false;
    return ::kill(pid_t(pid), 0) != 0 && errno == ESRCH;
}

std::string temporaryName(const fs::path& target, std::mt19937& rng) {
    char hex[9];
    std::snprintf(hex, sizeof hex, "%08x", static_cast<unsigned>(rng()));
    return target.filename().string() + ".tmp-" + std::to_string(long(::getpid())) + "-" + hex +
           target.extension().string();
}

}  // namespace

FileSink::FileSink(int fd, std::string displayPath) : m_fd(fd), m_path(std::move(displayPath)) {
    m_buffer.reserve(SINK_BUFFER_BYTES);
}

FileSink::~FileSink() {
    if (m_fd >= 0)
        ::close(m_fd);
}

void FileSink::fail(const char* action, int err) noexcept {
    if (m_error.empty()) {
        try {
            m_error = detail::concat("cannot write '", m_path, "': ", action,
                                     " failed: ", systemError(err));
        } catch (...) {
            m_error = "write failed";
        }
    }
}

void FileSink::throwIfFailed() const {
    if (!m_error.empty())
        throw IoError(m_error);
}

bool FileSink::flushBuffer() noexcept {
    if (m_buffer.empty() || failed())
        return !failed();
    if (m_fd < 0) {
        fail("write", EBADF);
        return false;
    }
    if (const int err = writeAll(m_fd, m_buffer.data(), m_buffer.size())) {
        fail("write", err);
        return false;
    }
    m_buffer.clear();
    return true;
}

bool FileSink::tryWrite(const void* data, size_t n) noexcept {
    if (failed())
        return false;
    const char* p = static_cast<const char*>(data);
    if (m_buffer.size() + n > SINK_BUFFER_BYTES) {
        if (!flushBuffer())
            return false;
        if (n >= SINK_BUFFER_BYTES) {
            if (const int err = writeAll(m_fd, p, n)) {
                fail("write", err);
                return false;
            }
            m_position += n;
            return true;
        }
    }
    m_buffer.append(p, n);
    m_position += n;
    return true;
}

void FileSink::write(const void* data, size_t n) {
    if (!tryWrite(data, n))
        throwIfFailed();
}

void FileSink::flush() {
    flushBuffer();
    throwIfFailed();
}

void FileSink::seek(uint64_t position) {
    flush();
    if (::lseek(m_fd, off_t(position), SEEK_SET) < 0) {
        fail("seek", errno);
        throwIfFailed();
    }
    m_position = position;
}

void FileSink::close() {
    if (m_fd < 0) {
        throwIfFailed();
        return;
    }
    flushBuffer();
    // fsync before the rename: otherwise a crash shortly after can leave the renamed file
    // empty on file systems that order metadata before data.
    if (!failed() && ::fsync(m_fd) != 0)
        fail("fsync", errno);
    if (::close(m_fd) != 0 && !failed())
        fail("close", errno);
    m_fd = -1;
    throwIfFailed();
}

AtomicFile::AtomicFile(std::string path) : m_path(std::move(path)) {
    LUCENT_CHECK(!m_path.empty(), "cannot write a file without a name");
    const fs::path target(m_path);
    LUCENT_CHECK(!target.filename().empty(), "cannot write '", m_path, "': not a file name");
    removeStaleTemporaries(m_path);
    std::mt19937 rng(std::random_device{}());
    for (int attempt = 0;; ++attempt) {
        m_tmp = (target.parent_path() / temporaryName(target, rng)).string();
        const int fd = ::open(m_tmp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            m_sink = new FileSink(fd, m_path);
            return;
        }
        const int err = errno;
        if (err != EEXIST || attempt == 16) {
            m_tmp.clear();
            LUCENT_THROW(IoError, "cannot write '", m_path, "': ", systemError(err));
        }
    }
}

AtomicFile::~AtomicFile() {
    delete m_sink;  // closes without checks: nothing of it is kept
    if (!m_committed && !m_tmp.empty())
        ::unlink(m_tmp.c_str());
}

FileSink& AtomicFile::sink() {
    LUCENT_CHECK(m_sink != nullptr, "AtomicFile '", m_path, "': the writer is already closed");
    return *m_sink;
}

void AtomicFile::releaseForExternalWriter() {
    delete m_sink;
    m_sink = nullptr;
    m_external = true;
}

void AtomicFile::finish() {
    if (m_finished)
        return;
    if (m_external) {
        const int fd = ::open(m_tmp.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd < 0)
            LUCENT_THROW(IoError, "cannot write '", m_path, "': the writer left no file (",
                         systemError(errno), ")");
        const int rc = ::fsync(fd);
        const int err = errno;
        ::close(fd);
        if (rc != 0)
            LUCENT_THROW(IoError, "cannot write '", m_path, "': fsync failed: ", systemError(err));
    } else {
        sink().close();
        delete m_sink;
        m_sink = nullptr;
    }
    m_finished = true;
}

void AtomicFile::commit() {
    if (m_committed)
        return;
    finish();
    if (::rename(m_tmp.c_str(), m_path.c_str()) != 0)
        LUCENT_THROW(IoError, "cannot write '", m_path, "': ", systemError(errno));
    m_committed = true;
    syncFolder(m_path);
}

void writeFileAtomically(const std::string& path, std::string_view bytes) {
    AtomicFile file(path);
    file.sink().write(bytes);
    file.commit();
}

void writeStreamAtomically(const std::string& path, const std::function<void(FileSink&)>& writer) {
    AtomicFile file(path);
    writer(file.sink());
    file.commit();
}

void writeFileAtomically(const std::string& path,
                         const std::function<void(const std::string& tmpPath)>& writer) {
    AtomicFile file(path);
    file.releaseForExternalWriter();
    writer(file.temporaryPath());
    file.commit();
}

size_t removeStaleTemporaries(const std::string& path) {
    const fs::path target(path);
    const std::string prefix = target.filename().string() + ".tmp-";
    const std::string ext = target.extension().string();
    fs::path dir = target.parent_path();
    if (dir.empty())
        dir = ".";
    std::error_code ec;
    fs::directory_iterator it(dir, ec);
    if (ec)
        return 0;
    size_t removed = 0;
    const auto now = fs::file_time_type::clock::now();
    for (; it != fs::directory_iterator(); it.increment(ec)) {
        if (ec)
            break;
        const std::string name = it->path().filename().string();
        if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0)
            continue;
        std::error_code sec;
        if (!fs::is_regular_file(fs::symlink_status(it->path(), sec)))
            continue;
        std::string_view rest(name);
        rest.remove_prefix(prefix.size());
        bool stale = false;
        if (allDigits(rest) && rest.size() <= 10) {
            // Written by earlier versions without the process id: stale once unmodified for
            // 10 minutes (a live writer keeps writing to it).
            const auto mtime = fs::last_write_time(it->path(), sec);
            stale = !sec && now - mtime > std::chrono::minutes(10);
        } else if (rest.size() > ext.size() + 10 &&
                   rest.compare(rest.size() - ext.size(), ext.size(), ext) == 0) {
            rest.remove_suffix(ext.size());
            const size_t dash = rest.find('-');
            if (dash != std::string_view::npos && allDigits(rest.substr(0, dash)) && dash <= 10 &&
                rest.size() - dash - 1 == 8 &&
                rest.substr(dash + 1).find_first_not_of("0123456789abcdef") ==
                    std::string_view::npos)
                stale = isProcessGone(std::stol(std::string(rest.substr(0, dash))));
        }
        if (stale && fs::remove(it->path(), sec))
            ++removed;
    }
    return removed;
}

}  // namespace lucent
