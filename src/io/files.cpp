#include "sdf_tracker/io/files.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <sys/stat.h>
#include <sys/statvfs.h>

namespace sdf_tracker::io {

namespace {

std::string temporaryPathFor(const std::string& path) { return path + ".tmp"; }

}  // namespace

void throwFileError(const std::string& path, const std::string& what) {
  throw std::runtime_error(path + ": " + what);
}

AtomicOutput::AtomicOutput(const std::string& path)
    : path_(path), temporary_(temporaryPathFor(path)), out_(temporary_, std::ios::binary | std::ios::trunc) {
  if (!out_) throwFileError(path_, std::string("cannot open for writing: ") + std::strerror(errno));
}

AtomicOutput::~AtomicOutput() {
  if (!committed_) std::remove(temporary_.c_str());
}

void AtomicOutput::commit() {
  out_.close();
  if (!out_) throwFileError(path_, "write failed (disk full?)");
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    throwFileError(path_, std::string("cannot move the written file into place: ") + std::strerror(errno));
  }
  committed_ = true;
}

std::ifstream openForReading(const std::string& path, uint64_t* size_bytes) {
  struct stat info;
  if (::stat(path.c_str(), &info) == 0 && !S_ISREG(info.st_mode)) {
    throwFileError(path, S_ISDIR(info.st_mode) ? "is a folder, not a file" : "is not a regular file (a FIFO or a device?)");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throwFileError(path, std::string("cannot open: ") + std::strerror(errno));
  if (size_bytes) {
    in.seekg(0, std::ios::end);
    *size_bytes = static_cast<uint64_t>(in.tellg());
    in.seekg(0);
  }
  return in;
}

void requireFreeSpace(const std::string& path, uint64_t bytes, const std::string& what) {
  std::error_code error;
  std::filesystem::path folder = std::filesystem::absolute(path, error).parent_path();
  struct statvfs disk;
  if (error || ::statvfs(folder.c_str(), &disk) != 0) return;  // opening the file then says what is wrong
  const uint64_t free_bytes = static_cast<uint64_t>(disk.f_bavail) * disk.f_frsize;
  if (free_bytes < bytes) {
    throwFileError(path, what + " needs about " + std::to_string(bytes >> 20) + " MiB, but " + folder.string() +
                             " has " + std::to_string(free_bytes >> 20) + " MiB free");
  }
}

bool hasExtension(const std::string& path, const std::string& extension) {
  return path.size() > extension.size() && path.compare(path.size() - extension.size(), extension.size(), extension) == 0;
}

void makeDirectories(const std::string& path) {
  std::string partial = !path.empty() && path[0] == '/' ? "/" : "";
  std::istringstream parts(path);
  std::string part;
  while (std::getline(parts, part, '/')) {
    if (part.empty()) continue;
    partial += part + "/";
    if (::mkdir(partial.c_str(), 0755) != 0 && errno != EEXIST) {
      throwFileError(partial, std::string("cannot create directory: ") + std::strerror(errno));
    }
  }
}

bool removeStaleTemporary(const std::string& path) {
  return std::remove(temporaryPathFor(path).c_str()) == 0;
}

void writeTextFile(const std::string& path, const std::string& text) {
  AtomicOutput out(path);
  out.stream() << text;
  out.commit();
}

}  // namespace sdf_tracker::io
