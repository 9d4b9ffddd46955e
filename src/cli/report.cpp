#include "sdf_tracker/cli/report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iomanip>
#include <sstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace sdf_tracker::tools {

namespace {

const cv::Scalar kWhite(255, 255, 255), kBlack(0, 0, 0), kGrey(200, 200, 200);
const cv::Scalar kGroundTruthColour(60, 60, 60), kEstimateColour(40, 90, 230), kErrorColour(200, 80, 20);

std::string fixed(double value, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << value;
  return s.str();
}

/// Maps data coordinates into a pixel rectangle, keeping the aspect ratio when asked.
struct PlotFrame {
  cv::Rect area;
  double x0, x1, y0, y1;

  PlotFrame(cv::Rect a, double xmin, double xmax, double ymin, double ymax, bool equal_aspect)
      : area(a), x0(xmin), x1(xmax), y0(ymin), y1(ymax) {
    const double pad_x = std::max(1e-6, 0.05 * (x1 - x0)), pad_y = std::max(1e-6, 0.05 * (y1 - y0));
    x0 -= pad_x, x1 += pad_x, y0 -= pad_y, y1 += pad_y;
    if (equal_aspect) {
      const double sx = (x1 - x0) / area.width, sy = (y1 - y0) / area.height, s = std::max(sx, sy);
      const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
      x0 = cx - 0.5 * s * area.width, x1 = cx + 0.5 * s * area.width;
      y0 = cy - 0.5 * s * area.height, y1 = cy + 0.5 * s * area.height;
    }
  }
  cv::Point toPixel(double x, double y) const {
    // Clamped before conversion: a wild estimate must not overflow int (undefined behaviour).
    auto pixel = [](double offset) { return static_cast<int>(std::clamp(std::isfinite(offset) ? offset : 0.0, -1e6, 1e6)); };
    return {area.x + pixel((x - x0) / (x1 - x0) * area.width),
            area.y + area.height - pixel((y - y0) / (y1 - y0) * area.height)};
  }
  void drawAxes(cv::Mat& image, const std::string& x_label, const std::string& y_label) const {
    cv::rectangle(image, area, kBlack, 1);
    for (int i = 0; i <= 4; ++i) {
      const double x = x0 + (x1 - x0) * i / 4.0, y = y0 + (y1 - y0) * i / 4.0;
      const cv::Point px = toPixel(x, y0), py = toPixel(x0, y);
      cv::line(image, {px.x, area.y}, {px.x, area.y + area.height}, kGrey, 1);
      cv::line(image, {area.x, py.y}, {area.x + area.width, py.y}, kGrey, 1);
      cv::putText(image, fixed(x, 2), {px.x - 18, area.y + area.height + 18}, cv::FONT_HERSHEY_SIMPLEX, 0.4, kBlack);
      cv::putText(image, fixed(y, 3), {area.x - 52, py.y + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4, kBlack);
    }
    cv::rectangle(image, area, kBlack, 1);
    cv::putText(image, x_label, {area.x + area.width / 2 - 30, area.y + area.height + 38}, cv::FONT_HERSHEY_SIMPLEX,
                0.5, kBlack);
    cv::putText(image, y_label, {area.x - 55, area.y - 8}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kBlack);
  }
};

void drawPolyline(cv::Mat& image, const PlotFrame& frame, const std::vector<cv::Point2d>& points, const cv::Scalar& colour) {
  for (size_t i = 1; i < points.size(); ++i) {
    cv::line(image, frame.toPixel(points[i - 1].x, points[i - 1].y), frame.toPixel(points[i].x, points[i].y), colour, 2,
             cv::LINE_AA);
  }
}

}  // namespace

Accuracy evaluateAccuracy(const std::vector<io::StampedPose>& estimate, const std::vector<io::StampedPose>& ground_truth) {
  return {evaluation::computeAte(estimate, ground_truth), evaluation::computeRpe(estimate, ground_truth)};
}

std::string formatAccuracy(const Accuracy& a) {
  std::ostringstream s;
  const auto& t = a.ate.translation_m;
  s << "ATE  RMSE " << fixed(t.rmse, 4) << " m   mean " << fixed(t.mean, 4) << "   median " << fixed(t.median, 4)
    << "   max " << fixed(t.max, 4) << "   (" << t.count << " poses)\n";
  if (a.rpe.translation_m_per_s.count > 0) {
    s << "RPE  RMSE " << fixed(a.rpe.translation_m_per_s.rmse, 4) << " m/s   " << fixed(a.rpe.rotation_deg_per_s.rmse, 3)
      << " deg/s   (1 s window, " << a.rpe.translation_m_per_s.count << " pairs)\n";
  } else {
    s << "RPE  n/a (trajectory shorter than the 1 s window)\n";
  }
  return s.str();
}

void writeAccuracyPlot(const std::string& path, const Accuracy& accuracy, const std::string& title) {
  const auto& gt = accuracy.ate.ground_truth;
  const auto& est = accuracy.ate.aligned_estimate;
  cv::Mat image(900, 800, CV_8UC3, kWhite);
  cv::putText(image, title, {20, 28}, cv::FONT_HERSHEY_SIMPLEX, 0.6, kBlack, 1, cv::LINE_AA);

  // Top view over the two axes along which the ground truth spreads most.
  Eigen::Vector3d lo = gt.front(), hi = gt.front();
  for (const auto& p : gt) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector3d span = hi - lo;
  std::vector<int> axes = {0, 1, 2};
  std::sort(axes.begin(), axes.end(), [&span](int i, int j) { return span[i] > span[j]; });
  const int a = std::min(axes[0], axes[1]), b = std::max(axes[0], axes[1]);
  std::vector<cv::Point2d> gt_2d, est_2d;
  double x0 = 1e9, x1 = -1e9, y0 = 1e9, y1 = -1e9;
  for (size_t i = 0; i < gt.size(); ++i) {
    gt_2d.emplace_back(gt[i][a], gt[i][b]);
    est_2d.emplace_back(est[i][a], est[i][b]);
    for (const auto& p : {gt_2d.back(), est_2d.back()}) x0 = std::min(x0, p.x), x1 = std::max(x1, p.x), y0 = std::min(y0, p.y), y1 = std::max(y1, p.y);
  }
  const char* names = "xyz";
  const PlotFrame top(cv::Rect(80, 60, 680, 470), x0, x1, y0, y1, true);
  top.drawAxes(image, std::string(1, names[a]) + " [m]", std::string(1, names[b]) + " [m]");
  drawPolyline(image, top, gt_2d, kGroundTruthColour);
  drawPolyline(image, top, est_2d, kEstimateColour);
  cv::putText(image, "ground truth", {600, 80}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kGroundTruthColour, 1, cv::LINE_AA);
  cv::putText(image, "estimate (aligned)", {600, 100}, cv::FONT_HERSHEY_SIMPLEX, 0.5, kEstimateColour, 1, cv::LINE_AA);

  // Error over time.
  const auto& times = accuracy.ate.timestamps_s;
  const auto& errors = accuracy.ate.errors_m;
  std::vector<cv::Point2d> error_2d;
  for (size_t i = 0; i < times.size(); ++i) error_2d.emplace_back(times[i] - times.front(), errors[i]);
  const double max_error = *std::max_element(errors.begin(), errors.end());
  const PlotFrame bottom(cv::Rect(80, 610, 680, 230), 0.0, std::max(1e-3, times.back() - times.front()), 0.0,
                         std::max(1e-4, max_error), false);
  bottom.drawAxes(image, "time [s]", "ATE [m]");
  drawPolyline(image, bottom, error_2d, kErrorColour);
  cv::putText(image, "RMSE " + fixed(accuracy.ate.translation_m.rmse, 4) + " m", {600, 630}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
              kErrorColour, 1, cv::LINE_AA);
  if (!cv::imwrite(path, image)) throw std::runtime_error(path + ": cannot write the plot");
}

std::string jsonString(const std::string& text) {
  std::string out = "\"";
  for (const char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (byte < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof(escaped), "\\u%04x", byte);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string jsonNumber(double value) {
  if (!std::isfinite(value)) return "null";
  std::ostringstream s;
  s << std::setprecision(9) << value;
  return s.str();
}

ProgressBar::ProgressBar(size_t total, bool enabled)
    : total_(std::max<size_t>(total, 1)), enabled_(enabled), start_(std::chrono::steady_clock::now()) {}

void ProgressBar::update(size_t done) {
  if (!enabled_) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const int width = 30;
  const int filled = static_cast<int>(width * done / total_);
  std::fprintf(stderr, "\r[%s%s] %zu/%zu frames  %.1f frames/s ", std::string(filled, '#').c_str(),
               std::string(width - filled, '.').c_str(), done, total_, elapsed > 0 ? done / elapsed : 0.0);
  std::fflush(stderr);
  line_open_ = true;
}

void ProgressBar::finish() {
  if (line_open_) std::fprintf(stderr, "\n");
  line_open_ = false;
}

ProgressBar::~ProgressBar() { finish(); }

}  // namespace sdf_tracker::tools
