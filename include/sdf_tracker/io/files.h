#pragma once

#include <cstdint>
#include <fstream>
#include <ostream>
#include <string>

/// What every file writer and reader of the package shares: errors that name the file, output
/// that appears under its final name only once complete, and directories. Every function throws
/// std::runtime_error naming the file and what is wrong with it.
namespace sdf_tracker::io {

/// Throws std::runtime_error("<path>: <what>").
[[noreturn]] void throwFileError(const std::string& path, const std::string& what);

/// An output file that appears under its final name only when commit() succeeds: it is written
/// to "<path>.tmp" and renamed into place, so a failed write never leaves a half-written file
/// under the final name (the temporary is removed when the object dies uncommitted).
class AtomicOutput {
 public:
  explicit AtomicOutput(const std::string& path);
  ~AtomicOutput();
  AtomicOutput(const AtomicOutput&) = delete;
  AtomicOutput& operator=(const AtomicOutput&) = delete;

  std::ofstream& stream() { return out_; }
  /// Closes the file and moves it into place; throws when either fails (disk full, ...).
  void commit();

 private:
  std::string path_;
  std::string temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes the bytes of a trivially copyable value (the files are little-endian, as this machine).
template <typename T>
void writeBinary(std::ostream& out, const T& value) {
  out.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

/// Opens `path` for reading (binary), and in `size_bytes`, when given, its length. Throws naming
/// the file when it cannot be opened, and when it is not a regular file (or a link to one): a
/// FIFO, a device or a folder given as a file would block a reader or feed it forever.
std::ifstream openForReading(const std::string& path, uint64_t* size_bytes = nullptr);

/// Throws when the file system `path` would be written to has less than `bytes` free: "<path>:
/// <what> needs about N MiB, but <folder> has M MiB free". Asked before a large write, so that a
/// full disk is named at the start rather than found half-way.
void requireFreeSpace(const std::string& path, uint64_t bytes, const std::string& what);

/// True when `path` ends in `extension` (".sdfmap") and has a name before it.
bool hasExtension(const std::string& path, const std::string& extension);

/// Creates a directory and any missing parents (like mkdir -p).
void makeDirectories(const std::string& path);

/// Writes text atomically (temporary file + rename).
void writeTextFile(const std::string& path, const std::string& text);

/// Removes the temporary file a writer of `path` left when its process was killed mid-write;
/// true when there was one.
bool removeStaleTemporary(const std::string& path);

}  // namespace sdf_tracker::io
