// SPDX-License-Identifier: MIT
#pragma once
/// @file
/// @brief Safe file input and output shared by every reader and writer of the engine
/// (docs/file-formats.md, "Import limits" and "Writing files"):
///   - import limits (file size, element counts, decoded bytes) that every importer checks
///     before an allocation proportional to what a file claims;
///   - atomic, checked writes: the bytes go to a temporary file beside the target, every write,
///     flush and close is checked, the temporary is fsync'ed before it is renamed over the
///     target and the folder after it; on any failure the temporary is removed and the old
///     file is kept. Temporaries left by killed runs are removed on the next write to the
///     same target.
///
///     writeFileAtomically("scene.json", text);                 // bytes already in memory
///     writeStreamAtomically("grid.vol", [&](FileSink& out) {    // streamed
///         out.write(header.data(), header.size());
///     });
///     AtomicFile a("a.vdb"), b("a.json");                        // two files, both or none
///     a.sink().write(...); b.sink().write(...);
///     a.commit(); b.commit();

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace lucent {

// ---------------------------------------------------------------------------------- input

/// Resource limits of every importer (meshes, scenes, VDB files, images). A file that exceeds
/// one is rejected with an IoError naming the limit, before the memory is allocated.
struct ImportLimits {
    uint64_t maxFileBytes = uint64_t(4) << 30;  ///< largest file an importer opens (4 GiB)
    /// Most elements (vertices, faces, list entries, tree nodes) a file may claim (2^27).
    uint64_t maxElements = uint64_t(1) << 27;
    /// Most memory a file may expand to when decoded, e.g. a compressed VDB tree (4 GiB).
    uint64_t maxDecodedBytes = uint64_t(4) << 30;
    /// CPU time of a reader run in a child process (lucent/core/Isolate.h), seconds.
    uint32_t maxReaderCpuSeconds = 120;
};

/// The process-wide limits (thread-safe).
ImportLimits importLimits();

/// Replaces the process-wide limits (thread-safe; meant for start-up and tests).
/// @throw ValueError if a limit is 0.
void setImportLimits(const ImportLimits& limits);

/// Sets the limits for the lifetime of the object, then restores the previous ones.
class ScopedImportLimits {
public:
    explicit ScopedImportLimits(const ImportLimits& limits);
    ~ScopedImportLimits();
    ScopedImportLimits(const ScopedImportLimits&) = delete;
    ScopedImportLimits& operator=(const ScopedImportLimits&) = delete;

private:
    ImportLimits m_previous;
};

/// Checks that `path` is an existing regular file (not a folder, a device such as /dev/zero,
/// or a FIFO) of at most importLimits().maxFileBytes.
/// @param what the kind of file for messages, e.g. "mesh file".
/// @return its size in bytes.
/// @throw IoError naming the file and the reason.
uint64_t checkInputFile(const std::string& path, const std::string& what);

/// Reads a whole file after checkInputFile.
/// @param maxBytes a tighter size limit for this kind of file (0: importLimits() only).
/// @throw IoError naming the file if it is missing, too large or unreadable.
std::string readInputFile(const std::string& path, const std::string& what, uint64_t maxBytes = 0);

/// Throws IoError "<what> '<path>' claims <count> <noun>, more than the import limit of ..."
/// when `count` exceeds importLimits().maxElements.
void checkElementCount(uint64_t count, const std::string& what, const std::string& path,
                       const char* noun);

// --------------------------------------------------------------------------------- output

/// A checked, buffered writer on an open file: every failed write, flush, seek or close
/// throws IoError (with the system's reason, e.g. "No space left on device") and is
/// remembered, so a caller that cannot let exceptions through (a C library callback, a
/// destructor) can ask failed() afterwards.
class FileSink {
public:
    FileSink(int fd, std::string displayPath);
    ~FileSink();
    FileSink(const FileSink&) = delete;
    FileSink& operator=(const FileSink&) = delete;

    /// Appends `n` bytes at the current position. @throw IoError on failure.
    void write(const void* data, size_t n);
    void write(std::string_view bytes) { write(bytes.data(), bytes.size()); }
    /// Same as write() without throwing: false on failure (the error is kept).
    bool tryWrite(const void* data, size_t n) noexcept;
    /// Moves the write position (flushes first). @throw IoError on failure.
    void seek(uint64_t position);
    [[nodiscard]] uint64_t position() const { return m_position; }
    /// Writes out the buffer. @throw IoError on failure.
    void flush();
    /// Flushes, fsyncs and closes the file. @throw IoError on failure (also for any earlier
    /// failure that was swallowed by a caller).
    void close();
    [[nodiscard]] bool failed() const { return !m_error.empty(); }
    /// The first failure's message, empty if none.
    [[nodiscard]] const std::string& error() const { return m_error; }

private:
    bool flushBuffer() noexcept;
    void fail(const char* action, int err) noexcept;
    void throwIfFailed() const;

    int m_fd;
    std::string m_path;
    std::string m_buffer;
    uint64_t m_position = 0;
    std::string m_error;
};

/// One atomic file replacement: the constructor removes stale temporaries of `path` (see
/// removeStaleTemporaries) and creates a fresh temporary beside it; commit() fsyncs, renames
/// it over `path` and fsyncs the folder; the destructor removes the temporary unless it was
/// committed. Several AtomicFile objects committed one after the other replace several files
/// only once all of them were written.
class AtomicFile {
public:
    /// @throw IoError if the temporary cannot be created (missing or read-only folder).
    explicit AtomicFile(std::string path);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// The writer on the temporary (valid until finish() or commit()).
    FileSink& sink();
    /// The temporary's path: for libraries that write to a file name themselves. It ends with
    /// the target's extension, so that writers choosing the format by extension work.
    [[nodiscard]] const std::string& temporaryPath() const { return m_tmp; }
    /// Closes our descriptor on the temporary so that a library may write it by name;
    /// finish() then fsyncs it by name.
    void releaseForExternalWriter();
    /// Checks, fsyncs and closes the temporary. @throw IoError on failure.
    void finish();
    /// finish() if needed, then renames the temporary over the target and fsyncs the folder.
    /// @throw IoError on failure (the temporary is removed, the target untouched).
    void commit();

private:
    std::string m_path;
    std::string m_tmp;
    FileSink* m_sink = nullptr;
    bool m_external = false;
    bool m_finished = false;
    bool m_committed = false;
};

/// Writes `bytes` to `path` atomically (see AtomicFile). @throw IoError naming `path`.
void writeFileAtomically(const std::string& path, std::string_view bytes);

/// Streams a file atomically: `writer` writes through the checked sink.
/// @throw IoError naming `path` (or whatever `writer` throws); the old file is then kept.
void writeStreamAtomically(const std::string& path, const std::function<void(FileSink&)>& writer);

/// For libraries that write to a file name: `writer(tmpPath)` writes the temporary, which is
/// then fsync'ed and renamed over `path`. Prefer writeStreamAtomically, which also sees
/// failed writes a library may swallow.
void writeFileAtomically(const std::string& path,
                         const std::function<void(const std::string& tmpPath)>& writer);

/// Removes temporaries that earlier, killed writes of `path` left beside it: names
/// `<file name>.tmp-<pid>-<8 hex digits><extension>` whose process no longer runs on this
/// host, and the older pattern `<file name>.tmp-<digits>` when unmodified for 10 minutes.
/// Nothing else is touched. @return how many were removed.
size_t removeStaleTemporaries(const std::string& path);

}  // namespace lucent
