#pragma once
// Closed-form least-squares rigid alignment without scale (Horn 1987 / Umeyama 1991 with the scale
// fixed to 1), as evaluate_ate.py of the TUM RGB-D tools computes it: the rotation R and
// translation t minimising sum_i |R model_i + t - data_i|^2. With centred points
// m_i = model_i - mean(model), d_i = data_i - mean(data), H = sum_i d_i m_i^T = U S V^T (SVD),
// R = U diag(1, 1, s) V^T with s = sign(det U det V) (a reflection is never returned), and
// t = mean(data) - R mean(model). When the points do not fix the rotation (fewer than three, or
// all on one line) R is one of the minimisers; the residuals are the same for all of them.

#include <cstddef>
#include <stdexcept>
#include <vector>

#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace cge {
namespace metrics {

namespace detail {

/// align_rigid over the pairs index(0) .. index(count - 1) of the two lists.
template <typename Index>
Eigen::Isometry3d align_rigid_over(const std::vector<Eigen::Vector3d>& model, const std::vector<Eigen::Vector3d>& data,
                                   std::size_t count, Index index) {
  Eigen::Vector3d model_mean = Eigen::Vector3d::Zero(), data_mean = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t i = index(k);
    if (!model[i].allFinite() || !data[i].allFinite())
      throw std::invalid_argument("align_rigid: a point is not finite");
    model_mean += model[i];
    data_mean += data[i];
  }
  model_mean /= static_cast<double>(count);
  data_mean /= static_cast<double>(count);
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t i = index(k);
    H += (data[i] - data_mean) * (model[i] - model_mean).transpose();
  }

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) S(2, 2) = -1;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = svd.matrixU() * S * svd.matrixV().transpose();
  T.translation() = data_mean - T.linear() * model_mean;
  return T;
}

}  // namespace detail

/// T with data_i ~ T * model_i (T_data_model). Throws std::invalid_argument for empty or
/// mismatched lists or non-finite points.
inline Eigen::Isometry3d align_rigid(const std::vector<Eigen::Vector3d>& model,
                                     const std::vector<Eigen::Vector3d>& data) {
  if (model.empty()) throw std::invalid_argument("align_rigid: no points");
  if (model.size() != data.size()) throw std::invalid_argument("align_rigid: the two point lists differ in length");
  return detail::align_rigid_over(model, data, model.size(), [](std::size_t k) { return k; });
}

/// The same over the pairs subset[0 .. count - 1] only (indices into both lists), without copying
/// them (a RANSAC fits many small subsets). Throws std::invalid_argument for an empty subset,
/// mismatched lists, an index outside them or non-finite points.
inline Eigen::Isometry3d align_rigid(const std::vector<Eigen::Vector3d>& model,
                                     const std::vector<Eigen::Vector3d>& data, const int* subset, std::size_t count) {
  if (count == 0) throw std::invalid_argument("align_rigid: no points");
  if (model.size() != data.size()) throw std::invalid_argument("align_rigid: the two point lists differ in length");
  for (std::size_t k = 0; k < count; ++k) {
    if (subset[k] < 0 || static_cast<std::size_t>(subset[k]) >= model.size())
      throw std::invalid_argument("align_rigid: a subset index is outside the point lists");
  }
  return detail::align_rigid_over(model, data, count,
                                  [subset](std::size_t k) { return static_cast<std::size_t>(subset[k]); });
}

}  // namespace metrics
}  // namespace cge
