#include "sdf_tracker/devices/oni_file.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace sdf_tracker::devices {

namespace {

// The recording format's constants (OpenNI 2: Source/Core/OniDataRecords.h, PlayerNode, XnCodecIDs).
constexpr uint32_t kRecordMagic = 0x0052494E;  // "NIR\0"
enum RecordType : uint32_t {
  kIntProperty = 0x03,
  kGeneralProperty = 0x06,
  kNodeRemoved = 0x07,
  kNodeDataBegin = 0x08,
  kNodeStateReady = 0x09,
  kNewData = 0x0A,
  kEnd = 0x0B,
  kNodeAdded = 0x0D,
  kSeekTable = 0x0E,
};
constexpr uint32_t kDepthNodeType = 2;
constexpr uint32_t kImageNodeType = 3;
constexpr uint32_t kUncompressed = ('E' << 24) | ('N' << 16) | ('O' << 8) | 'N';  // "NONE"
constexpr uint64_t kPixelFormatGrey16 = 4;                                       // OpenNI 1.x
constexpr uint64_t kPixelFormatRgb24 = 1;                                        // OpenNI 1.x
constexpr uint64_t kOniPixelFormatDepth1mm = 100;                                // ONI_PIXEL_FORMAT_DEPTH_1_MM
constexpr uint64_t kOniPixelFormatRgb888 = 200;                                  // ONI_PIXEL_FORMAT_RGB888
constexpr uint32_t kSupportsGrey16 = 1u << 3;                                    // XnSupportedPixelFormats
constexpr uint32_t kSupportsRgb24 = 1u << 0;
constexpr uint64_t kMaxDepth_mm = 10000;

/// Little helper to lay out a record's fields as the format packs them (no padding, host order).
class Fields {
 public:
  template <typename T>
  Fields& add(const T& value) {
    return addBytes(&value, sizeof(T));
  }
  Fields& addBytes(const void* data, size_t size) {
    const size_t end = data_.size();
    data_.resize(end + size);
    std::memcpy(data_.data() + end, data, size);
    return *this;
  }
  /// Strings: length including the terminating NUL, then the characters and the NUL.
  Fields& addString(const std::string& text) {
    add(static_cast<uint32_t>(text.size() + 1));
    return addBytes(text.c_str(), text.size() + 1);
  }
  const std::vector<uint8_t>& bytes() const { return data_; }

 private:
  std::vector<uint8_t> data_;
};

}  // namespace

OniRecordingWriter::OniRecordingWriter(std::string path, const PinholeCamera& camera, bool with_colour, int fps)
    : path_(std::move(path)), temporary_(path_ + ".partial"), width_(camera.width), height_(camera.height) {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write " + temporary_);
  const auto pixels = static_cast<uint32_t>(width_) * static_cast<uint32_t>(height_);
  streams_.reserve(2);
  streams_.emplace_back(1, "Depth", kDepthNodeType, pixels * 2);
  if (with_colour) streams_.emplace_back(2, "Image", kImageNodeType, pixels * 3);
  writeFileHeader(std::numeric_limits<uint64_t>::max());
  for (auto& stream : streams_) addStream(&stream, camera, fps);
  // Then, as OpenNI's Recorder starts recording: each stream ready and its data begun. OniFile
  // opens a recording by reading up to the first data begun, so every stream is added before.
  for (const auto& stream : streams_) {
    writeRecord(kNodeStateReady, stream.node_id, 0, {});
    writeRecord(kNodeDataBegin, stream.node_id, 0,
                Fields().add(std::numeric_limits<uint32_t>::max()).add(std::numeric_limits<uint64_t>::max()).bytes());
  }
}

OniRecordingWriter::~OniRecordingWriter() {
  if (!finished_) {
    out_.close();
    std::remove(temporary_.c_str());
  }
}

uint64_t OniRecordingWriter::position() { return static_cast<uint64_t>(out_.tellp()); }

void OniRecordingWriter::writeFileHeader(uint64_t max_timestamp_us) {
  const char identity[4] = {'N', 'I', '1', '0'};
  // Version 1.0.1.0: major, minor (bytes), maintenance (16 bits), build (32 bits).
  Fields header;
  header.addBytes(identity, 4).add(uint8_t{1}).add(uint8_t{0}).add(uint16_t{1}).add(uint32_t{0});
  header.add(max_timestamp_us).add(streams_.back().node_id);  // the highest node id
  out_.write(reinterpret_cast<const char*>(header.bytes().data()), static_cast<std::streamsize>(header.bytes().size()));
}

void OniRecordingWriter::addStream(Stream* stream, const PinholeCamera& camera, int fps) {
  const bool depth = stream->node_type == kDepthNodeType;
  stream->node_added_position = position();
  writeNodeAdded(*stream, 0);
  writeIntProperty(stream, "oniRequiredFrameSize", stream->frame_bytes);
  writeIntProperty(stream, "xnIsGenerating", 1);
  if (depth) writeIntProperty(stream, "xnDeviceMaxDepth", kMaxDepth_mm);
  const uint32_t mode[3] = {static_cast<uint32_t>(width_), static_cast<uint32_t>(height_), static_cast<uint32_t>(fps)};
  writeIntProperty(stream, "xnSupportedMapOutputModesCount", 1);
  writeProperty(stream, kGeneralProperty, "xnSupportedMapOutputModes", mode, sizeof(mode));
  writeProperty(stream, kGeneralProperty, "xnMapOutputMode", mode, sizeof(mode));
  writeProperty(stream, kGeneralProperty, "xnSupportedPixelFormats", depth ? &kSupportsGrey16 : &kSupportsRgb24,
                sizeof(uint32_t));
  writeIntProperty(stream, "xnPixelFormat", depth ? kPixelFormatGrey16 : kPixelFormatRgb24);
  writeIntProperty(stream, "oniPixelFormat", depth ? kOniPixelFormatDepth1mm : kOniPixelFormatRgb888);
  // OpenNI describes intrinsics by the field of view; the principal point goes to the calibration
  // file. The colour camera's is the depth camera's: the recording's depth is registered to it.
  const double fov[2] = {2.0 * std::atan(camera.width / (2.0 * camera.fx)),
                         2.0 * std::atan(camera.height / (2.0 * camera.fy))};
  writeProperty(stream, kGeneralProperty, "xnFOV", fov, sizeof(fov));
  // OniFile hands out no frame of a stream without a cropping state, so it is recorded (off), and
  // the mirroring state (off) with it.
  writeIntProperty(stream, "Cropping", 1);
  const Fields cropping = Fields().add(int32_t{0}).add(uint16_t{0}).add(uint16_t{0}).add(uint16_t{0}).add(uint16_t{0});
  writeProperty(stream, kGeneralProperty, "xnCropping", cropping.bytes().data(),
                static_cast<uint32_t>(cropping.bytes().size()));
  writeIntProperty(stream, "Mirror", 1);
  writeIntProperty(stream, "xnMirror", 0);
}

void OniRecordingWriter::writeRecord(uint32_t type, uint32_t node_id, uint64_t undo_position,
                                     const std::vector<uint8_t>& fields, const uint8_t* payload,
                                     uint32_t payload_size) {
  constexpr uint32_t kHeaderSize = 5 * sizeof(uint32_t) + sizeof(uint64_t);
  Fields header;
  header.add(kRecordMagic).add(type).add(node_id).add(static_cast<uint32_t>(kHeaderSize + fields.size()));
  header.add(payload_size).add(undo_position);
  out_.write(reinterpret_cast<const char*>(header.bytes().data()), static_cast<std::streamsize>(header.bytes().size()));
  out_.write(reinterpret_cast<const char*>(fields.data()), static_cast<std::streamsize>(fields.size()));
  if (payload_size > 0) out_.write(reinterpret_cast<const char*>(payload), payload_size);
  if (!out_) throw std::runtime_error("cannot write " + temporary_);
}

void OniRecordingWriter::writeNodeAdded(const Stream& stream, uint64_t seek_table_position) {
  const bool known = seek_table_position != 0;  // at finish(); before, the maxima stand in
  writeRecord(kNodeAdded, stream.node_id, 0,
              Fields()
                  .addString(stream.name)
                  .add(stream.node_type)
                  .add(kUncompressed)
                  .add(known ? static_cast<uint32_t>(stream.frames.size()) : std::numeric_limits<uint32_t>::max())
                  .add(uint64_t{0})
                  .add(known && !stream.frames.empty() ? stream.frames.back().timestamp_us
                                                       : std::numeric_limits<uint64_t>::max())
                  .add(seek_table_position)
                  .bytes());
}

void OniRecordingWriter::writeProperty(Stream* stream, uint32_t type, const std::string& name, const void* data,
                                       uint32_t size) {
  const uint64_t here = position();
  writeRecord(type, stream->node_id, stream->last_property_position[name],
              Fields().addString(name).add(size).addBytes(data, size).bytes());
  stream->last_property_position[name] = here;
}

void OniRecordingWriter::writeIntProperty(Stream* stream, const std::string& name, uint64_t value) {
  writeProperty(stream, kIntProperty, name, &value, sizeof(value));
}

void OniRecordingWriter::addDepth(uint64_t timestamp_us, const std::vector<uint16_t>& depth_mm) {
  if (depth_mm.size() != static_cast<size_t>(width_) * height_) {
    throw std::invalid_argument("a depth frame of the recording has " + std::to_string(width_) + "x" +
                                std::to_string(height_) + " depths, got " + std::to_string(depth_mm.size()));
  }
  addFrame(&streams_.front(), timestamp_us, reinterpret_cast<const uint8_t*>(depth_mm.data()), depth_mm.size() * 2);
}

void OniRecordingWriter::addColour(uint64_t timestamp_us, const ColourImage& colour) {
  if (streams_.size() < 2) throw std::logic_error("the recording " + path_ + " was opened without colour");
  const std::string mismatch = colour.sizeMismatch(width_, height_);
  if (!mismatch.empty()) throw std::invalid_argument(mismatch);
  addFrame(&streams_[1], timestamp_us, colour.data(), static_cast<size_t>(width_) * height_ * 3);
}

void OniRecordingWriter::addFrame(Stream* stream, uint64_t timestamp_us, const uint8_t* data, size_t bytes) {
  if (!stream->frames.empty() && timestamp_us <= stream->frames.back().timestamp_us) {
    throw std::invalid_argument(stream->name + " frame timestamps must increase (" + std::to_string(timestamp_us) +
                                " us after " + std::to_string(stream->frames.back().timestamp_us) + " us)");
  }
  const uint64_t here = position();
  const auto frame_number = static_cast<uint32_t>(stream->frames.size() + 1);
  writeRecord(kNewData, stream->node_id, stream->last_frame_position,
              Fields().add(timestamp_us).add(frame_number).bytes(), data, static_cast<uint32_t>(bytes));
  stream->last_frame_position = here;
  stream->frames.push_back({timestamp_us, here});
}

void OniRecordingWriter::finish() {
  std::vector<uint64_t> seek_table_positions;
  for (const auto& stream : streams_) {
    writeRecord(kNodeRemoved, stream.node_id, stream.node_added_position, {});
    // The seek table: an empty entry, then one per frame (timestamp, configuration id, position).
    seek_table_positions.push_back(position());
    Fields table;
    table.add(uint64_t{0}).add(uint32_t{0}).add(uint64_t{0});
    for (const auto& frame : stream.frames) table.add(frame.timestamp_us).add(uint32_t{0}).add(frame.position);
    writeRecord(kSeekTable, stream.node_id, 0, {}, table.bytes().data(), static_cast<uint32_t>(table.bytes().size()));
  }
  writeRecord(kEnd, 0, 0, {});  // the end record belongs to no stream
  // Now that they are known: the frame counts, the last timestamps and where the seek tables are.
  uint64_t max_timestamp_us = 0;
  for (const auto& stream : streams_) {
    if (!stream.frames.empty()) max_timestamp_us = std::max(max_timestamp_us, stream.frames.back().timestamp_us);
  }
  out_.seekp(0);
  writeFileHeader(max_timestamp_us);
  for (size_t i = 0; i < streams_.size(); ++i) {
    out_.seekp(static_cast<std::streamoff>(streams_[i].node_added_position));
    writeNodeAdded(streams_[i], seek_table_positions[i]);
  }
  out_.close();
  if (!out_) throw std::runtime_error("cannot write " + temporary_);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error("cannot rename " + temporary_ + " to " + path_ + ": " + std::strerror(errno));
  }
  finished_ = true;
}

}  // namespace sdf_tracker::devices
