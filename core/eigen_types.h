#pragma once
// Eigen aliases used across hapsim. Fixed-size types for per-element kernels so element loops
// allocate nothing; ConstRef for read-only inputs that accept any compatible expression.

#include <Eigen/Core>

namespace hapsim {

template <typename T>
using ConstRef = const Eigen::Ref<const T>&;

using Vector12d = Eigen::Matrix<double, 12, 1>;
using Matrix12d = Eigen::Matrix<double, 12, 12>;
using Matrix3Xd = Eigen::Matrix<double, 3, Eigen::Dynamic>;
using Matrix4Xi = Eigen::Matrix<int, 4, Eigen::Dynamic>;
using Matrix3Xi = Eigen::Matrix<int, 3, Eigen::Dynamic>;
using Matrix6Xi = Eigen::Matrix<int, 6, Eigen::Dynamic>;

}  // namespace hapsim
