#include "sdf_tracker/devices/fakenect_dump.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

namespace sdf_tracker::devices {

namespace fs = std::filesystem;

FakenectDumpWriter::FakenectDumpWriter(std::string folder) : folder_(std::move(folder)), staging_(folder_ + ".partial") {
  if (fs::exists(folder_)) throw std::runtime_error(folder_ + " already exists; choose a new folder for the recording");
  fs::remove_all(staging_);  // left by a conversion that was killed
  fs::create_directories(staging_);
}

FakenectDumpWriter::~FakenectDumpWriter() {
  if (!finished_) {
    std::error_code ignored;
    fs::remove_all(staging_, ignored);
  }
}

void FakenectDumpWriter::addDepth(double time_s, const std::vector<uint16_t>& disparities) {
  if (disparities.size() != static_cast<size_t>(fakenect::kWidth) * fakenect::kHeight) {
    throw std::invalid_argument("a fakenect depth frame has 640x480 values, got " + std::to_string(disparities.size()));
  }
  addEvent('d', time_s, "pgm", "P5 640 480 65535", disparities.data(), disparities.size() * sizeof(uint16_t));
}

void FakenectDumpWriter::addColour(double time_s, const ColourImage& colour) {
  const std::string mismatch = colour.sizeMismatch(fakenect::kWidth, fakenect::kHeight);
  if (!mismatch.empty()) throw std::invalid_argument("fakenect records 640x480 colour: " + mismatch);
  addEvent('r', time_s, "ppm", "P6 640 480 255", colour.data(), size_t{3} * fakenect::kWidth * fakenect::kHeight);
}

void FakenectDumpWriter::addEvent(char type, double time_s, const char* extension, const std::string& header,
                                  const void* pixels, size_t bytes) {
  if (index_.empty()) first_time_s_ = time_s;
  // The device's own frame clock is not kept by a TUM sequence: microseconds since the first
  // event stand in for it (libfreenect passes it to the callback; nothing here reads it).
  const auto device_timestamp = static_cast<uint32_t>(std::llround((time_s - first_time_s_) * 1e6) & 0xffffffffLL);
  char name[96];
  std::snprintf(name, sizeof(name), "%c-%f-%u.%s", type, time_s, device_timestamp, extension);
  const std::string path = staging_ + "/" + name;
  std::ofstream out(path, std::ios::binary);
  out << header << "\n";
  out.write(static_cast<const char*>(pixels), static_cast<std::streamsize>(bytes));
  if (!out.flush()) throw std::runtime_error("cannot write " + path);
  index_.emplace_back(name);
}

void FakenectDumpWriter::finish() {
  const std::string index_path = staging_ + "/" + fakenect::kIndexFile;
  std::ofstream index(index_path);
  for (const auto& name : index_) index << name << "\n";
  if (!index.flush()) throw std::runtime_error("cannot write " + index_path);
  index.close();
  fs::rename(staging_, folder_);
  finished_ = true;
}

namespace {

/// Why `path` does not hold a whole image whose header starts with `magic` ("P5": depth, "P6":
/// colour) and whose pixels take `bytes_per_pixel`, or "".
std::string imageFileProblem(const std::string& path, const char* magic, int bytes_per_pixel) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return "cannot be opened";
  std::string header;
  std::getline(in, header);
  int width = 0, height = 0;
  if (std::sscanf(header.c_str(), (std::string(magic) + " %d %d").c_str(), &width, &height) != 2 ||
      width != fakenect::kWidth || height != fakenect::kHeight) {
    return "has the header \"" + header.substr(0, 40) + "\", not \"" + magic + " 640 480 <maximum>\"";
  }
  const uint64_t needed = header.size() + 1 + uint64_t(bytes_per_pixel) * fakenect::kWidth * fakenect::kHeight;
  std::error_code error;
  const uint64_t bytes = fs::file_size(path, error);
  if (error || bytes < needed) {
    return "holds " + std::to_string(error ? 0 : bytes) + " bytes of the " + std::to_string(needed) +
           " a 640x480 image needs (cut short?)";
  }
  return "";
}

}  // namespace

FakenectFrames readFakenectFrames(const std::string& folder) {
  const std::string path = folder + "/" + fakenect::kIndexFile;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path + " (not a fakenect recording?)");
  FakenectFrames frames;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty()) continue;
    char type = 0;
    double time_s = 0.0;
    unsigned int timestamp = 0;
    if (std::sscanf(line.c_str(), "%c-%lf-%u", &type, &time_s, &timestamp) != 3) {
      throw std::runtime_error(path + " line " + std::to_string(number) + ": \"" + line +
                               "\" is not <type>-<seconds>-<timestamp>.<ext>");
    }
    if (type != 'd' && type != 'r') continue;
    FakenectFrame frame;
    frame.time_s = time_s;
    frame.file = folder + "/" + line;
    frame.problem = type == 'd' ? imageFileProblem(frame.file, "P5", 2) : imageFileProblem(frame.file, "P6", 3);
    (type == 'd' ? frames.depth : frames.colour).push_back(std::move(frame));
  }
  return frames;
}

}  // namespace sdf_tracker::devices
