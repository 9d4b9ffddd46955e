#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "sdf_tracker/camera/camera.h"
#include "sdf_tracker/camera/colour_image.h"

namespace sdf_tracker::devices {

/// Writes an OpenNI recording (.oni) of a depth stream (16-bit millimetres) and optionally a
/// colour stream (8-bit RGB), both uncompressed, in the layout OpenNI 2's own Recorder writes and
/// its OniFile driver plays: a file header; per stream its properties (video mode, pixel format,
/// the camera's field of view); one record per frame with its timestamp in microseconds, the
/// streams' frames interleaved in the order they are added; per stream a seek table; an end
/// record. The file is written to "<path>.partial" and renamed by finish(): a failed conversion
/// leaves no playable file. Throws std::runtime_error naming the file on any failure.
class OniRecordingWriter {
 public:
  /// A depth stream of the camera's size at `fps` frames per second and, with `with_colour`, a
  /// colour stream of the same size and rate.
  OniRecordingWriter(std::string path, const PinholeCamera& camera, bool with_colour = false, int fps = 30);
  ~OniRecordingWriter();
  OniRecordingWriter(const OniRecordingWriter&) = delete;
  OniRecordingWriter& operator=(const OniRecordingWriter&) = delete;

  /// One depth frame of width x height depths in mm (0: no depth); a stream's timestamps must increase.
  void addDepth(uint64_t timestamp_us, const std::vector<uint16_t>& depth_mm);
  /// One colour frame of width x height (needs `with_colour`).
  void addColour(uint64_t timestamp_us, const ColourImage& colour);
  void finish();

 private:
  struct SeekEntry {
    uint64_t timestamp_us;
    uint64_t position;
  };
  /// One stream ("node" in the format's words) and what finish() must write of it.
  struct Stream {
    Stream(uint32_t id, std::string stream_name, uint32_t type, uint32_t bytes_per_frame)
        : node_id(id), name(std::move(stream_name)), node_type(type), frame_bytes(bytes_per_frame) {}
    uint32_t node_id;
    std::string name;
    uint32_t node_type;
    uint32_t frame_bytes;
    uint64_t node_added_position = 0, last_frame_position = 0;
    std::vector<SeekEntry> frames;
    std::map<std::string, uint64_t> last_property_position;
  };
  uint64_t position();
  void addStream(Stream* stream, const PinholeCamera& camera, int fps);
  void addFrame(Stream* stream, uint64_t timestamp_us, const uint8_t* data, size_t bytes);
  void writeRecord(uint32_t type, uint32_t node_id, uint64_t undo_position, const std::vector<uint8_t>& fields,
                   const uint8_t* payload = nullptr, uint32_t payload_size = 0);
  void writeNodeAdded(const Stream& stream, uint64_t seek_table_position);
  void writeProperty(Stream* stream, uint32_t type, const std::string& name, const void* data, uint32_t size);
  void writeIntProperty(Stream* stream, const std::string& name, uint64_t value);
  void writeFileHeader(uint64_t max_timestamp_us);

  std::string path_, temporary_;
  int width_, height_;
  std::ofstream out_;
  std::vector<Stream> streams_;  ///< depth, then colour
  bool finished_ = false;
};

}  // namespace sdf_tracker::devices
