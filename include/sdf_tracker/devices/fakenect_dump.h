#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sdf_tracker/camera/colour_image.h"

namespace sdf_tracker::devices {

/// A libfreenect "fakenect" recording: a folder with INDEX.txt naming one file per event, in the
/// order they are replayed, as fakenect-record writes it. Depth frames are
/// "d-<seconds>-<device timestamp>.pgm": a one-line PGM header, then 640x480 raw 11-bit
/// disparities as 16-bit values in the machine's byte order (what the device callback receives).
/// Colour images are "r-<seconds>-<device timestamp>.ppm": a one-line PPM header, then 640x480
/// pixels of 8-bit RGB. The seconds are the wall-clock time of the recording; fakenect replays
/// the files in INDEX.txt's order with the same gaps.
namespace fakenect {
constexpr int kWidth = 640;
constexpr int kHeight = 480;
constexpr const char* kIndexFile = "INDEX.txt";
}  // namespace fakenect

/// Writes a recording into a new folder. Everything goes to "<folder>.partial" first and is
/// renamed when finish() is called, so a killed conversion never leaves a folder fakenect would
/// play. Throws std::runtime_error naming the file on any failure.
class FakenectDumpWriter {
 public:
  /// Refuses an existing folder (it would mix two recordings).
  explicit FakenectDumpWriter(std::string folder);
  ~FakenectDumpWriter();
  FakenectDumpWriter(const FakenectDumpWriter&) = delete;
  FakenectDumpWriter& operator=(const FakenectDumpWriter&) = delete;

  /// One depth frame of kWidth x kHeight raw disparities recorded at time_s (seconds). Frames
  /// and colour images are replayed in the order they are added.
  void addDepth(double time_s, const std::vector<uint16_t>& disparities);
  /// One colour image of kWidth x kHeight recorded at time_s (seconds).
  void addColour(double time_s, const ColourImage& colour);
  /// The folder being written, where other files belonging to the recording go.
  const std::string& stagingFolder() const { return staging_; }
  void finish();

 private:
  /// Writes one event's file: "<type>-<time_s>-<device timestamp>.<extension>", the header line, the pixels.
  void addEvent(char type, double time_s, const char* extension, const std::string& header, const void* pixels,
                size_t bytes);

  std::string folder_, staging_;
  std::vector<std::string> index_;
  double first_time_s_ = 0.0;
  bool finished_ = false;
};

/// One depth frame or colour image of a recording, as its INDEX.txt lists it.
struct FakenectFrame {
  double time_s = 0.0;  ///< when it was recorded
  std::string file;     ///< its path
  /// Why fakenect would hand on less than a whole image (a file cut short, a missing file, a
  /// header that is not "P5 640 480 ..." for depth, "P6 640 480 ..." for colour), or empty when
  /// the file holds the whole image.
  std::string problem;
};

/// What a recording holds, each in replay order.
struct FakenectFrames {
  std::vector<FakenectFrame> depth;
  std::vector<FakenectFrame> colour;
};

/// The depth frames and colour images of a recording from its INDEX.txt (other events, such as
/// the accelerometer's, are left out), each file checked for a whole image. Throws
/// std::runtime_error naming the file and line if INDEX.txt cannot be read.
FakenectFrames readFakenectFrames(const std::string& folder);

}  // namespace sdf_tracker::devices
