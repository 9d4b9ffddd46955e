#include "sdf_tracker/io/tum_sequence.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include <sys/stat.h>

#include "sdf_tracker/io/colour_image_file.h"
#include "sdf_tracker/io/depth_png.h"

namespace sdf_tracker {

namespace {

bool fileExists(const std::string& path) {
  struct stat info;
  return ::stat(path.c_str(), &info) == 0;
}

/// Reads "fx fy cx cy width height depth_factor [k1 k2 p1 p2 k3]" (after '#' comments); returns
/// whether the line gave the distortion.
bool readIntrinsicsFile(const std::string& path, PinholeCamera* camera, double* depth_factor) {
  std::ifstream in(path);
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    if (!(words >> camera->fx >> camera->fy >> camera->cx >> camera->cy >> camera->width >> camera->height >>
          *depth_factor)) {
      throw std::runtime_error(path + ": expected \"" + std::string(TumSequence::kIntrinsicsColumns) + "\", got \"" +
                               line + "\"");
    }
    LensDistortion& d = camera->distortion;
    if (!(words >> d.k1)) return false;
    if (!(words >> d.k2 >> d.p1 >> d.p2 >> d.k3) || !(words >> std::ws).eof()) {
      throw std::runtime_error(path + ": expected \"" + std::string(TumSequence::kIntrinsicsColumns) +
                               "\" (all five distortion coefficients or none), got \"" + line + "\"");
    }
    return true;
  }
  throw std::runtime_error(path + ": no intrinsics line");
}

/// A file a list names: relative to the sequence's folder, as TUM writes them, or absolute.
std::string listedPath(const std::string& directory, const std::string& name) {
  return !name.empty() && name[0] == '/' ? name : directory + "/" + name;
}

}  // namespace

std::vector<TimedLine> readTimedList(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::vector<TimedLine> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    TimedLine timed;
    timed.line_number = number;
    if (!(fields >> timed.timestamp_s) || !std::isfinite(timed.timestamp_s)) {
      throw std::runtime_error(path + ": line " + std::to_string(number) + " does not start with a timestamp: \"" +
                               line + "\"");
    }
    std::getline(fields >> std::ws, timed.rest);
    lines.push_back(std::move(timed));
  }
  return lines;
}

std::string TimedLine::firstWord() const {
  std::istringstream words(rest);
  std::string word;
  words >> word;
  return word;
}

std::vector<long> associateByTime(const std::vector<double>& a, const std::vector<double>& b, double max_difference_s) {
  // Every pair within reach (b sorted by time for the search), closest first; ties in list order.
  std::vector<size_t> b_order(b.size());
  for (size_t j = 0; j < b.size(); ++j) b_order[j] = j;
  std::sort(b_order.begin(), b_order.end(), [&b](size_t x, size_t y) { return b[x] < b[y]; });
  std::vector<std::tuple<double, size_t, size_t>> pairs;  // |difference|, index in a, index in b
  for (size_t i = 0; i < a.size(); ++i) {
    auto first = std::lower_bound(b_order.begin(), b_order.end(), a[i] - max_difference_s,
                                  [&b](size_t j, double t) { return b[j] < t; });
    for (auto it = first; it != b_order.end() && b[*it] <= a[i] + max_difference_s; ++it) {
      pairs.emplace_back(std::fabs(a[i] - b[*it]), i, *it);
    }
  }
  std::sort(pairs.begin(), pairs.end());
  std::vector<long> partner(a.size(), -1);
  std::vector<char> taken(b.size(), 0);
  for (const auto& [difference, i, j] : pairs) {
    if (partner[i] >= 0 || taken[j]) continue;
    partner[i] = static_cast<long>(j);
    taken[j] = 1;
  }
  return partner;
}

TumSequence TumSequence::open(const std::string& directory, const SequenceOptions& options) {
  TumSequence sequence;
  const std::string list_path = directory + "/depth.txt";
  if (!fileExists(list_path)) {
    throw std::runtime_error(list_path + ": cannot open (is " + directory + " a TUM-layout sequence?)");
  }
  for (const TimedLine& entry : readTimedList(list_path)) {
    const std::string relative = entry.firstWord();
    if (relative.empty()) {
      throw std::runtime_error(list_path + ": line " + std::to_string(entry.line_number) +
                               " is not \"timestamp filename\": it names no file");
    }
    if (!sequence.frames_.empty() && entry.timestamp_s <= sequence.frames_.back().timestamp_s) {
      throw std::runtime_error(list_path + ": line " + std::to_string(entry.line_number) + " has timestamp " +
                               std::to_string(entry.timestamp_s) + ", not after the previous frame's");
    }
    Frame frame;
    frame.timestamp_s = entry.timestamp_s;
    frame.path = listedPath(directory, relative);
    sequence.frames_.push_back(std::move(frame));
  }
  if (sequence.frames_.empty()) throw std::runtime_error(list_path + ": lists no depth frames");

  const std::string colour_list_path = directory + "/rgb.txt";
  if (fileExists(colour_list_path)) {
    sequence.has_colour_list_ = true;
    const std::vector<TimedLine> colour = readTimedList(colour_list_path);
    std::vector<double> depth_times, colour_times;
    for (const Frame& frame : sequence.frames_) depth_times.push_back(frame.timestamp_s);
    for (const TimedLine& entry : colour) colour_times.push_back(entry.timestamp_s);
    const std::vector<long> partner = associateByTime(depth_times, colour_times, kMaxColourGap_s);
    for (size_t i = 0; i < partner.size(); ++i) {
      if (partner[i] < 0) continue;
      const TimedLine& entry = colour[static_cast<size_t>(partner[i])];
      const std::string relative = entry.firstWord();
      if (relative.empty()) {
        throw std::runtime_error(colour_list_path + ": line " + std::to_string(entry.line_number) + " names no image");
      }
      sequence.frames_[i].colour_path = listedPath(directory, relative);
      sequence.frames_[i].colour_timestamp_s = entry.timestamp_s;
    }
  }

  // TUM's downloads carry no intrinsics file; their folder's name says which camera took them, and
  // so which calibration TUM publishes for them, lens distortion included.
  std::filesystem::path folder = std::filesystem::path(directory).lexically_normal();
  if (folder.filename().empty()) folder = folder.parent_path();  // "dir/"
  const std::string named = PinholeCamera::tumCameraMentionedIn(folder.filename().string());
  sequence.camera_ = named.empty() ? PinholeCamera::tumFreiburg1() : *PinholeCamera::tumCamera(named);
  sequence.intrinsics_source_ =
      named.empty() ? "TUM freiburg1 defaults" : "TUM " + named + "'s published calibration, from the folder's name";
  bool distortion_stated = false;
  const std::string intrinsics_path = directory + "/intrinsics.txt";
  if (fileExists(intrinsics_path)) {
    sequence.camera_ = PinholeCamera::tumFreiburg1();  // what the file does not state is not a TUM camera's
    distortion_stated = readIntrinsicsFile(intrinsics_path, &sequence.camera_, &sequence.depth_factor_);
    sequence.intrinsics_source_ = "intrinsics.txt";
  } else {
    distortion_stated = !named.empty();
  }
  if (options.camera) {
    sequence.camera_ = *options.camera;
    sequence.intrinsics_source_ = "options";
    distortion_stated = false;
  }
  sequence.distortion_source_ = distortion_stated ? sequence.intrinsics_source_ : "none stated";
  if (options.depth_factor) sequence.depth_factor_ = *options.depth_factor;
  if (!(sequence.depth_factor_ > 0.0)) {
    throw std::runtime_error(directory + ": depth factor must be > 0 (got " + std::to_string(sequence.depth_factor_) +
                             ")");
  }
  if (options.distortion) {
    sequence.camera_.distortion = *options.distortion;
    sequence.distortion_source_ = "options";
    distortion_stated = true;
  }
  if (!distortion_stated) {
    // Say what the numbers suggest, and do nothing about it: the data states no distortion.
    const std::string tum = PinholeCamera::tumCameraWithIntrinsicsOf(sequence.camera_);
    if (!tum.empty()) {
      const LensDistortion d = PinholeCamera::tumCamera(tum)->distortion;  // a copy: tumCamera returns a value
      std::ostringstream hint;
      hint << "these are TUM " << tum << "'s intrinsics, but no lens distortion is stated, so none is removed; if "
           << "the images are TUM's, state the distortion TUM publishes for them: " << d.k1 << " " << d.k2 << " "
           << d.p1 << " " << d.p2 << " " << d.k3 << " as intrinsics.txt's last five columns, or sdf_tracker_offline "
           << "--distortion " << d.k1 << "," << d.k2 << "," << d.p1 << "," << d.p2 << "," << d.k3;
      sequence.distortion_hint_ = hint.str();
    }
  }
  const auto violations = sequence.camera_.validate();
  if (!violations.empty()) throw std::runtime_error(directory + ": invalid intrinsics: " + violations.front());
  const std::string gt_path = directory + "/groundtruth.txt";
  if (fileExists(gt_path)) sequence.ground_truth_ = io::readTrajectory(gt_path);
  return sequence;
}

DepthImage TumSequence::depth(size_t i) const {
  DepthImage image = io::readDepthPng(depthPath(i), depth_factor_);
  if (image.width() != camera_.width || image.height() != camera_.height) {
    std::ostringstream msg;
    msg << depthPath(i) << ": image is " << image.width() << "x" << image.height() << " but the intrinsics are for "
        << camera_.width << "x" << camera_.height;
    throw std::runtime_error(msg.str());
  }
  return image;
}

size_t TumSequence::colouredFrames() const {
  return static_cast<size_t>(
      std::count_if(frames_.begin(), frames_.end(), [](const Frame& frame) { return !frame.colour_path.empty(); }));
}

std::optional<ColourImage> TumSequence::colour(size_t i) const {
  const std::string& path = colourPath(i);
  if (path.empty()) return std::nullopt;
  return io::readColourImage(path, camera_.width, camera_.height);
}

}  // namespace sdf_tracker
