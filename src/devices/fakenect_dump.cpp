#include "sdf_tracker/devices/fakenect_dump.h"

#include <cmath>
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
  if (index_.empty()) first_time_s_ = time_s;
  // The device's own frame clock is not kept by a TUM sequence: microseconds since the first
  // frame stand in for it (libfreenect passes it to the callback; nothing here reads it).
  const auto device_timestamp = static_cast<uint32_t>(std::llround((time_s - first_time_s_) * 1e6) & 0xffffffffLL);
  char name[96];
  std::snprintf(name, sizeof(name), "d-%f-%u.pgm", time_s, device_timestamp);
  const std::string path = staging_ + "/" + name;
  std::ofstream out(path, std::ios::binary);
  out << "P5 " << fakenect::kWidth << " " << fakenect::kHeight << " 65535\n";
  out.write(reinterpret_cast<const char*>(disparities.data()),
            static_cast<std::streamsize>(disparities.size() * sizeof(uint16_t)));
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

std::vector<double> readFakenectDepthTimes(const std::string& folder) {
  const std::string path = folder + "/" + fakenect::kIndexFile;
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path + " (not a fakenect recording?)");
  std::vector<double> times;
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
    if (type == 'd') times.push_back(time_s);
  }
  return times;
}

}  // namespace sdf_tracker::devices
