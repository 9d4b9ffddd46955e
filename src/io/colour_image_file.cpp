#include "sdf_tracker/io/colour_image_file.h"

#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sdf_tracker/io/depth_png.h"
#include "sdf_tracker/io/files.h"

namespace sdf_tracker::io {

ColourImage readColourImage(const std::string& path, int expected_width, int expected_height) {
  openForReading(path);  // a missing file is named as such, not as an image that does not decode
  // A PNG's header says what it holds before anything is decoded; a JPEG is always 8-bit.
  if (!hasExtension(path, ".jpg") && !hasExtension(path, ".jpeg")) {
    const PngHeader header = readPngHeader(path);
    if (header.bit_depth != 8) {
      throwFileError(path, "a colour image must hold 8 bits a channel (got " + header.describe() + ")");
    }
  }
  const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty() || bgr.type() != CV_8UC3) throwFileError(path, "cannot decode the colour image (corrupt?)");
  if (expected_width > 0 && (bgr.cols != expected_width || bgr.rows != expected_height)) {
    throwFileError(path, "colour image is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                             " but the depth images are " + std::to_string(expected_width) + "x" +
                             std::to_string(expected_height) + ": colour must be registered to the depth");
  }
  ColourImage image(bgr.cols, bgr.rows);
  cv::Mat rgb(bgr.rows, bgr.cols, CV_8UC3, image.data());
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  return image;
}

void writeColourImage(const std::string& path, const ColourImage& image) {
  const bool jpeg = hasExtension(path, ".jpg") || hasExtension(path, ".jpeg");
  if (!jpeg && !hasExtension(path, ".png")) throwFileError(path, "unknown image extension (known: .png, .jpg, .jpeg)");
  const cv::Mat rgb(image.height(), image.width(), CV_8UC3, const_cast<uint8_t*>(image.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<uchar> encoded;
  const std::vector<int> options = jpeg ? std::vector<int>{cv::IMWRITE_JPEG_QUALITY, 90} : std::vector<int>{};
  if (!cv::imencode(jpeg ? ".jpg" : ".png", bgr, encoded, options)) throwFileError(path, "image encoding failed");
  AtomicOutput out(path);
  out.stream().write(reinterpret_cast<const char*>(encoded.data()), static_cast<std::streamsize>(encoded.size()));
  out.commit();
}

}  // namespace sdf_tracker::io
