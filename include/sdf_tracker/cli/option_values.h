#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "sdf_tracker/camera/camera.h"

/// The values of the command-line tools' options that are more than one number. Each throws
/// std::invalid_argument naming the option (as the user typed it, e.g. "--initial-pose") and the
/// text when the value cannot be read.
namespace sdf_tracker::tools {

/// Comma-separated numbers: "1,2.5,-3".
std::vector<double> parseNumberList(const std::string& option, const std::string& text);
/// A pose TX,TY,TZ,QX,QY,QZ,QW (metres and a unit quaternion, within 1e-3).
Eigen::Isometry3d parsePose(const std::string& option, const std::string& text);
/// Lens distortion K1,K2,P1,P2,K3 (OpenCV's plumb bob).
LensDistortion parseDistortion(const std::string& option, const std::string& text);
/// FX,FY,CX,CY[,W,H] over `base` (which keeps its size when W,H are not given).
PinholeCamera parseIntrinsics(const std::string& option, const std::string& text, const PinholeCamera& base);
/// A box X0,Y0,Z0,X1,Y1,Z1 with X0 < X1, Y0 < Y1, Z0 < Z1.
Eigen::AlignedBox3d parseBox(const std::string& option, const std::string& text);

}  // namespace sdf_tracker::tools
