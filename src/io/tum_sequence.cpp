#include "sdf_tracker/io/tum_sequence.h"

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <sys/stat.h>

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

}  // namespace

TumSequence TumSequence::open(const std::string& directory, const SequenceOptions& options) {
  TumSequence sequence;
  const std::string list_path = directory + "/depth.txt";
  std::ifstream list(list_path);
  if (!list) throw std::runtime_error(list_path + ": cannot open (is " + directory + " a TUM-layout sequence?)");
  std::string line;
  int line_number = 0;
  while (std::getline(list, line)) {
    ++line_number;
    if (line.empty() || line[0] == '#') continue;
    std::istringstream words(line);
    Frame frame;
    std::string relative;
    if (!(words >> frame.timestamp_s >> relative)) {
      throw std::runtime_error(list_path + ": line " + std::to_string(line_number) +
                               " is not \"timestamp filename\": " + line);
    }
    if (!sequence.frames_.empty() && frame.timestamp_s <= sequence.frames_.back().timestamp_s) {
      throw std::runtime_error(list_path + ": line " + std::to_string(line_number) + " has timestamp " +
                               std::to_string(frame.timestamp_s) + ", not after the previous frame's");
    }
    frame.path = directory + "/" + relative;
    sequence.frames_.push_back(frame);
  }
  if (sequence.frames_.empty()) throw std::runtime_error(list_path + ": lists no depth frames");

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

}  // namespace sdf_tracker
