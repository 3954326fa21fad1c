// robotdyn/kernels/common.hpp: what every kernel of the compiled evaluator shares (robotdyn/_compiled.cpp).
//
// The kernels under robotdyn/kernels/ are the C++ twins of robotdyn's Python reference formulas, one header per
// constraint kind or reduction step, each named like its Python module (rolling_contact.hpp beside
// robotdyn/constraints/rolling_contact.py, ...). They are header-only, included by robotdyn/_compiled.cpp (one
// translation unit: the Evaluator's orchestration and the Python bindings), and work on the buffers the Evaluator
// passes them, so that an evaluation allocates nothing once the buffers are sized. Derivatives of a kernel go
// beside it as <kind>_derivatives.hpp (as Pinocchio puts rnea-derivatives.hpp beside rnea.hpp).
#pragma once

#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/model.hpp>
#include <pinocchio/algorithm/crba.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/jacobian.hpp>
#include <pinocchio/algorithm/kinematics.hpp>
#include <pinocchio/algorithm/frames.hpp>

#include <Eigen/QR>
#include <Eigen/SVD>

#include <stdexcept>

namespace robotdyn {
namespace kernels {

namespace pin = pinocchio;
using Eigen::Matrix3d;
using Eigen::MatrixXd;
using Eigen::Vector3d;
using Eigen::VectorXd;
using RowMat = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using Matrix6x = Eigen::Matrix<double, 6, Eigen::Dynamic>;

// A failure the Python side handles by falling back to the reference path (which raises the proper error).
struct Fallback : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// [x]_x, the cross-product matrix (robotdyn/constraints/constraint.py: skew)
inline Matrix3d skew(const Vector3d& x) {
  Matrix3d m;
  m << 0.0, -x[2], x[1], x[2], 0.0, -x[0], -x[1], x[0], 0.0;
  return m;
}

// Frame fid's classical acceleration in LOCAL_WORLD_ALIGNED axes, given its velocity v in the same axes (as
// pin::getFrameVelocity gives it): pin::getFrameClassicalAcceleration's formula and operations (spatial acceleration
// plus omega x v), without computing the frame's velocity a second time.
inline pin::Motion classical_acceleration(const pin::Model& model, const pin::Data& data, int fid, const pin::Motion& v) {
  pin::Motion acc = pin::getFrameAcceleration(model, data, static_cast<pin::FrameIndex>(fid), pin::LOCAL_WORLD_ALIGNED);
  acc.linear() += v.angular().cross(v.linear());
  return acc;
}

}  // namespace kernels
}  // namespace robotdyn
