#include "sdf_tracker/io/depth_png.h"

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "sdf_tracker/io/files.h"

namespace sdf_tracker::io {

std::string PngHeader::describe() const {
  const char* kind = colour_type == 0   ? "greyscale"
                     : colour_type == 2 ? "RGB"
                     : colour_type == 3 ? "palette"
                     : colour_type == 4 ? "greyscale + alpha"
                     : colour_type == 6 ? "RGBA"
                                        : "unknown colour type";
  return std::to_string(bit_depth) + "-bit " + kind;
}

PngHeader readPngHeader(const std::string& path) {
  std::ifstream in = openForReading(path);
  unsigned char bytes[26];
  in.read(reinterpret_cast<char*>(bytes), sizeof(bytes));
  static const unsigned char kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (in.gcount() != sizeof(bytes) || std::memcmp(bytes, kSignature, 8) != 0 || std::memcmp(bytes + 12, "IHDR", 4) != 0) {
    throwFileError(path, "not a PNG file (no PNG signature and header)");
  }
  auto bigEndian = [&](int at) {
    return (static_cast<uint32_t>(bytes[at]) << 24) | (static_cast<uint32_t>(bytes[at + 1]) << 16) |
           (static_cast<uint32_t>(bytes[at + 2]) << 8) | bytes[at + 3];
  };
  const uint32_t width = bigEndian(16), height = bigEndian(20);
  if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu) {
    throwFileError(path, "PNG header gives an invalid size " + std::to_string(width) + "x" + std::to_string(height));
  }
  return {static_cast<int>(width), static_cast<int>(height), bytes[24], bytes[25]};
}

DepthImage readDepthPng(const std::string& path, double depth_factor, int expected_width, int expected_height) {
  if (!(depth_factor > 0.0 && std::isfinite(depth_factor))) {
    throwFileError(path, "depth factor must be > 0 (got " + std::to_string(depth_factor) + ")");
  }
  const PngHeader header = readPngHeader(path);
  if (header.colour_type != 0 || header.bit_depth != 16) {
    throwFileError(path, "depth must be a 16-bit greyscale PNG (got " + header.describe() + ")");
  }
  if (expected_width > 0 && (header.width != expected_width || header.height != expected_height)) {
    throwFileError(path, "image is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                   " but the intrinsics are for " + std::to_string(expected_width) + "x" +
                   std::to_string(expected_height));
  }
  if (static_cast<long long>(header.width) * header.height > kMaxImagePixels) {
    throwFileError(path, "image is " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                   ", larger than any depth camera's (at most " + std::to_string(kMaxImagePixels) + " pixels)");
  }
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE);
  if (raw.empty()) throwFileError(path, "cannot decode the PNG (corrupt?)");
  if (raw.type() != CV_16UC1 || raw.cols != header.width || raw.rows != header.height) {
    throwFileError(path, "decoded image does not match its PNG header (corrupt?)");
  }
  return DepthImage::fromRaw16(raw.ptr<uint16_t>(), raw.cols, raw.rows, depth_factor);
}

void writeDepthPng(const std::string& path, const DepthImage& depth, double depth_factor) {
  std::vector<uint16_t> values = depth.toRaw16(depth_factor);
  const cv::Mat raw(depth.height(), depth.width(), CV_16UC1, values.data());
  std::vector<uchar> png;
  if (!cv::imencode(".png", raw, png)) throwFileError(path, "PNG encoding failed");
  AtomicOutput out(path);
  out.stream().write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  out.commit();
}

}  // namespace sdf_tracker::io
