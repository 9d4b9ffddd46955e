#include "sdf_tracker/devices/oni_file.h"

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
constexpr uint32_t kNodeId = 1;
constexpr uint32_t kUncompressed = ('E' << 24) | ('N' << 16) | ('O' << 8) | 'N';  // "NONE"
constexpr uint64_t kPixelFormatGrey16 = 4;                                       // OpenNI 1.x
constexpr uint64_t kOniPixelFormatDepth1mm = 100;                                // ONI_PIXEL_FORMAT_DEPTH_1_MM
constexpr uint32_t kSupportsGrey16 = 1u << 3;                                    // XnSupportedPixelFormats
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

OniDepthWriter::OniDepthWriter(std::string path, const PinholeCamera& camera, int fps)
    : path_(std::move(path)), temporary_(path_ + ".partial"), width_(camera.width), height_(camera.height) {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) throw std::runtime_error("cannot write " + temporary_);
  writeFileHeader(std::numeric_limits<uint64_t>::max());
  node_added_position_ = position();
  writeNodeAdded(std::numeric_limits<uint32_t>::max(), std::numeric_limits<uint64_t>::max(), 0);

  const uint32_t frame_bytes = static_cast<uint32_t>(width_) * height_ * 2;
  writeIntProperty("oniRequiredFrameSize", frame_bytes);
  writeIntProperty("xnIsGenerating", 1);
  writeIntProperty("xnDeviceMaxDepth", kMaxDepth_mm);
  const uint32_t mode[3] = {static_cast<uint32_t>(width_), static_cast<uint32_t>(height_), static_cast<uint32_t>(fps)};
  writeIntProperty("xnSupportedMapOutputModesCount", 1);
  writeProperty(kGeneralProperty, "xnSupportedMapOutputModes", mode, sizeof(mode));
  writeProperty(kGeneralProperty, "xnMapOutputMode", mode, sizeof(mode));
  writeProperty(kGeneralProperty, "xnSupportedPixelFormats", &kSupportsGrey16, sizeof(kSupportsGrey16));
  writeIntProperty("xnPixelFormat", kPixelFormatGrey16);
  writeIntProperty("oniPixelFormat", kOniPixelFormatDepth1mm);
  // OpenNI describes intrinsics by the field of view; the principal point goes to the calibration file.
  const double fov[2] = {2.0 * std::atan(camera.width / (2.0 * camera.fx)),
                         2.0 * std::atan(camera.height / (2.0 * camera.fy))};
  writeProperty(kGeneralProperty, "xnFOV", fov, sizeof(fov));
  // OniFile hands out no frame of a stream without a cropping state, so it is recorded (off), and
  // the mirroring state (off) with it.
  writeIntProperty("Cropping", 1);
  const Fields cropping = Fields().add(int32_t{0}).add(uint16_t{0}).add(uint16_t{0}).add(uint16_t{0}).add(uint16_t{0});
  writeProperty(kGeneralProperty, "xnCropping", cropping.bytes().data(), static_cast<uint32_t>(cropping.bytes().size()));
  writeIntProperty("Mirror", 1);
  writeIntProperty("xnMirror", 0);
  writeRecord(kNodeStateReady, 0, {});
  writeRecord(kNodeDataBegin, 0,
              Fields().add(std::numeric_limits<uint32_t>::max()).add(std::numeric_limits<uint64_t>::max()).bytes());
}

OniDepthWriter::~OniDepthWriter() {
  if (!finished_) {
    out_.close();
    std::remove(temporary_.c_str());
  }
}

uint64_t OniDepthWriter::position() { return static_cast<uint64_t>(out_.tellp()); }

void OniDepthWriter::writeFileHeader(uint64_t max_timestamp_us) {
  const char identity[4] = {'N', 'I', '1', '0'};
  // Version 1.0.1.0: major, minor (bytes), maintenance (16 bits), build (32 bits).
  Fields header;
  header.addBytes(identity, 4).add(uint8_t{1}).add(uint8_t{0}).add(uint16_t{1}).add(uint32_t{0});
  header.add(max_timestamp_us).add(kNodeId);
  out_.write(reinterpret_cast<const char*>(header.bytes().data()), static_cast<std::streamsize>(header.bytes().size()));
}

void OniDepthWriter::writeRecord(uint32_t type, uint64_t undo_position, const std::vector<uint8_t>& fields,
                                 const uint8_t* payload, uint32_t payload_size) {
  constexpr uint32_t kHeaderSize = 5 * sizeof(uint32_t) + sizeof(uint64_t);
  Fields header;
  const uint32_t node_id = type == kEnd ? 0 : kNodeId;  // the end record belongs to no stream
  header.add(kRecordMagic).add(type).add(node_id).add(static_cast<uint32_t>(kHeaderSize + fields.size()));
  header.add(payload_size).add(undo_position);
  out_.write(reinterpret_cast<const char*>(header.bytes().data()), static_cast<std::streamsize>(header.bytes().size()));
  out_.write(reinterpret_cast<const char*>(fields.data()), static_cast<std::streamsize>(fields.size()));
  if (payload_size > 0) out_.write(reinterpret_cast<const char*>(payload), payload_size);
  if (!out_) throw std::runtime_error("cannot write " + temporary_);
}

void OniDepthWriter::writeNodeAdded(uint32_t frames, uint64_t max_timestamp_us, uint64_t seek_table_position) {
  writeRecord(kNodeAdded, 0,
              Fields()
                  .addString("Depth")
                  .add(kDepthNodeType)
                  .add(kUncompressed)
                  .add(frames)
                  .add(uint64_t{0})
                  .add(max_timestamp_us)
                  .add(seek_table_position)
                  .bytes());
}

void OniDepthWriter::writeProperty(uint32_t type, const std::string& name, const void* data, uint32_t size) {
  const uint64_t here = position();
  writeRecord(type, last_property_position_[name], Fields().addString(name).add(size).addBytes(data, size).bytes());
  last_property_position_[name] = here;
}

void OniDepthWriter::writeIntProperty(const std::string& name, uint64_t value) {
  writeProperty(kIntProperty, name, &value, sizeof(value));
}

void OniDepthWriter::addFrame(uint64_t timestamp_us, const std::vector<uint16_t>& depth_mm) {
  if (depth_mm.size() != static_cast<size_t>(width_) * height_) {
    throw std::invalid_argument("a frame of the recording has " + std::to_string(width_) + "x" +
                                std::to_string(height_) + " depths, got " + std::to_string(depth_mm.size()));
  }
  if (!frames_.empty() && timestamp_us <= last_timestamp_us_) {
    throw std::invalid_argument("frame timestamps must increase (" + std::to_string(timestamp_us) + " us after " +
                                std::to_string(last_timestamp_us_) + " us)");
  }
  const uint64_t here = position();
  const auto frame_number = static_cast<uint32_t>(frames_.size() + 1);
  writeRecord(kNewData, last_frame_position_, Fields().add(timestamp_us).add(frame_number).bytes(),
              reinterpret_cast<const uint8_t*>(depth_mm.data()), static_cast<uint32_t>(depth_mm.size() * 2));
  last_frame_position_ = here;
  last_timestamp_us_ = timestamp_us;
  frames_.push_back({timestamp_us, here});
}

void OniDepthWriter::finish() {
  writeRecord(kNodeRemoved, node_added_position_, {});
  // The seek table: an empty entry, then one per frame (timestamp, configuration id, position).
  const uint64_t seek_table_position = position();
  Fields table;
  table.add(uint64_t{0}).add(uint32_t{0}).add(uint64_t{0});
  for (const auto& frame : frames_) table.add(frame.timestamp_us).add(uint32_t{0}).add(frame.position);
  writeRecord(kSeekTable, 0, {}, table.bytes().data(), static_cast<uint32_t>(table.bytes().size()));
  writeRecord(kEnd, 0, {});
  // Now that they are known: the frame count, the last timestamp and where the seek table is.
  const uint64_t max_timestamp_us = frames_.empty() ? 0 : frames_.back().timestamp_us;
  out_.seekp(0);
  writeFileHeader(max_timestamp_us);
  out_.seekp(static_cast<std::streamoff>(node_added_position_));
  writeNodeAdded(static_cast<uint32_t>(frames_.size()), max_timestamp_us, seek_table_position);
  out_.close();
  if (!out_) throw std::runtime_error("cannot write " + temporary_);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error("cannot rename " + temporary_ + " to " + path_ + ": " + std::strerror(errno));
  }
  finished_ = true;
}

}  // namespace sdf_tracker::devices
