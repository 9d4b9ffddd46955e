#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include "sdf_tracker/camera/camera.h"

namespace sdf_tracker::devices {

/// Writes an OpenNI recording (.oni) of one depth stream (16-bit millimetres, uncompressed), in
/// the layout OpenNI 2's own Recorder writes and its OniFile driver plays: a file header, the
/// stream's properties (video mode, pixel format, the camera's field of view), one record per frame with its
/// timestamp in microseconds, a seek table and an end record. The file is written to
/// "<path>.partial" and renamed by finish(): a failed conversion leaves no playable file.
/// Throws std::runtime_error naming the file on any failure.
class OniDepthWriter {
 public:
  /// A stream of the camera's size at `fps` frames per second.
  OniDepthWriter(std::string path, const PinholeCamera& camera, int fps = 30);
  ~OniDepthWriter();
  OniDepthWriter(const OniDepthWriter&) = delete;
  OniDepthWriter& operator=(const OniDepthWriter&) = delete;

  /// One frame of width x height depths in mm (0: no depth); timestamps must increase.
  void addFrame(uint64_t timestamp_us, const std::vector<uint16_t>& depth_mm);
  void finish();

 private:
  struct SeekEntry {
    uint64_t timestamp_us;
    uint64_t position;
  };
  uint64_t position();
  void writeRecord(uint32_t type, uint64_t undo_position, const std::vector<uint8_t>& fields,
                   const uint8_t* payload = nullptr, uint32_t payload_size = 0);
  void writeNodeAdded(uint32_t frames, uint64_t max_timestamp_us, uint64_t seek_table_position);
  void writeProperty(uint32_t type, const std::string& name, const void* data, uint32_t size);
  void writeIntProperty(const std::string& name, uint64_t value);
  void writeFileHeader(uint64_t max_timestamp_us);

  std::string path_, temporary_;
  int width_, height_;
  std::ofstream out_;
  uint64_t node_added_position_ = 0, last_frame_position_ = 0, last_timestamp_us_ = 0;
  std::map<std::string, uint64_t> last_property_position_;
  std::vector<SeekEntry> frames_;
  bool finished_ = false;
};

}  // namespace sdf_tracker::devices
