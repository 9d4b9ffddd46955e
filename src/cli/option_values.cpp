#include "sdf_tracker/cli/option_values.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

#include "sdf_tracker/cli/command_line.h"
#include "sdf_tracker/pipeline/parameters.h"

namespace sdf_tracker::tools {

std::vector<double> parseNumberList(const std::string& option, const std::string& text) {
  // Every field between commas is a number: "1,2," has an empty third one, as ",1,2" a first.
  std::vector<double> values;
  for (size_t start = 0;; ) {
    const size_t comma = text.find(',', start);
    values.push_back(parseNumber(option, text.substr(start, comma == std::string::npos ? std::string::npos : comma - start)));
    if (comma == std::string::npos) return values;
    start = comma + 1;
  }
}

Eigen::Isometry3d parsePose(const std::string& option, const std::string& text) {
  const std::vector<double> v = parseNumberList(option, text);
  if (v.size() != 7) throw std::invalid_argument(option + ": expected TX,TY,TZ,QX,QY,QZ,QW, got \"" + text + "\"");
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (std::abs(q.norm() - 1.0) > 1e-3) {
    throw std::invalid_argument(option + " " + text + ": the quaternion QX,QY,QZ,QW has norm " +
                                std::to_string(q.norm()) + ", not 1");
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

LensDistortion parseDistortion(const std::string& option, const std::string& text) {
  const std::vector<double> v = parseNumberList(option, text);
  if (v.size() != 5) throw std::invalid_argument(option + ": expected K1,K2,P1,P2,K3, got \"" + text + "\"");
  return {v[0], v[1], v[2], v[3], v[4]};
}

PinholeCamera parseIntrinsics(const std::string& option, const std::string& text, const PinholeCamera& base) {
  const std::vector<double> v = parseNumberList(option, text);
  if (v.size() != 4 && v.size() != 6) {
    throw std::invalid_argument(option + ": expected FX,FY,CX,CY[,W,H], got \"" + text + "\"");
  }
  PinholeCamera camera = base;
  camera.fx = v[0], camera.fy = v[1], camera.cx = v[2], camera.cy = v[3];
  if (v.size() == 6) {
    camera.width = wholeNumber(v[4], option + ": the width W", text);
    camera.height = wholeNumber(v[5], option + ": the height H", text);
  }
  return camera;
}

Eigen::AlignedBox3d parseBox(const std::string& option, const std::string& text) {
  const std::vector<double> v = parseNumberList(option, text);
  if (v.size() != 6 || !(v[0] < v[3] && v[1] < v[4] && v[2] < v[5])) {
    throw std::invalid_argument(option + ": expected X0,Y0,Z0,X1,Y1,Z1 with X0 < X1, Y0 < Y1, Z0 < Z1, got \"" +
                                text + "\"");
  }
  return Eigen::AlignedBox3d(Eigen::Vector3d(v[0], v[1], v[2]), Eigen::Vector3d(v[3], v[4], v[5]));
}

}  // namespace sdf_tracker::tools
