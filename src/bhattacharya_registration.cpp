/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/bhattacharya_registration.h>
#include <pcl_movers/impl/bhattacharya_registration.hpp>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

namespace pcl_movers {
namespace detail {

void refinePeak(int dims, const bool* active, const std::function<float(const int*)>& sample,
                float* offsets, float* value) {
  std::vector<int> act;
  for (int d = 0; d < dims; ++d) {
    offsets[d] = 0.f;
    if (active[d]) act.push_back(d);
  }
  std::vector<int> o(static_cast<std::size_t>(dims), 0);
  const float centre = sample(o.data());
  *value = centre;
  const int k = static_cast<int>(act.size());
  if (k == 0) return;

  // Full quadratic f(u) = c + gᵀu + ½ uᵀHu, least squares over the 3^k neighbourhood: captures
  // the tilt of a peak between yaw layers and translations, which independent parabolas miss.
  int count = 1;
  for (int i = 0; i < k; ++i) count *= 3;
  const int terms = 1 + k + k * (k + 1) / 2;
  Eigen::MatrixXd a(count, terms);
  Eigen::VectorXd b(count);
  for (int s = 0; s < count; ++s) {
    int rem = s;
    std::vector<double> u(static_cast<std::size_t>(k));
    for (int i = 0; i < k; ++i) {
      const int ui = rem % 3 - 1;
      rem /= 3;
      u[static_cast<std::size_t>(i)] = ui;
      o[static_cast<std::size_t>(act[static_cast<std::size_t>(i)])] = ui;
    }
    int c = 0;
    a(s, c++) = 1.0;
    for (int i = 0; i < k; ++i) a(s, c++) = u[static_cast<std::size_t>(i)];
    for (int i = 0; i < k; ++i)
      for (int j = i; j < k; ++j)
        a(s, c++) = u[static_cast<std::size_t>(i)] * u[static_cast<std::size_t>(j)];
    b(s) = sample(o.data());
  }
  const Eigen::VectorXd coef = a.colPivHouseholderQr().solve(b);
  Eigen::VectorXd g(k);
  Eigen::MatrixXd h(k, k);
  int c = 1;
  for (int i = 0; i < k; ++i) g(i) = coef(c++);
  for (int i = 0; i < k; ++i)
    for (int j = i; j < k; ++j) {
      const double q = coef(c++);
      if (i == j)
        h(i, i) = 2.0 * q;
      else
        h(i, j) = h(j, i) = q;
    }
  Eigen::LLT<Eigen::MatrixXd> neg(-h);
  if (neg.info() == Eigen::Success) {
    const Eigen::VectorXd u = neg.solve(g);  // -H u = g  →  u = -H⁻¹ g
    if (u.allFinite() && u.cwiseAbs().maxCoeff() <= 1.0) {
      for (int i = 0; i < k; ++i)
        offsets[act[static_cast<std::size_t>(i)]] = static_cast<float>(u(i));
      *value = static_cast<float>(coef(0) + g.dot(u) + 0.5 * u.dot(h * u));
      return;
    }
  }
  // Fallback: one parabola per dimension through (-1, 0, +1).
  std::fill(o.begin(), o.end(), 0);
  float gain = 0.f;
  for (int d : act) {
    o[static_cast<std::size_t>(d)] = -1;
    const float fm = sample(o.data());
    o[static_cast<std::size_t>(d)] = 1;
    const float fp = sample(o.data());
    o[static_cast<std::size_t>(d)] = 0;
    const float curv = fm - 2.f * centre + fp;
    if (curv < 0.f) {
      const float u = std::min(std::max(0.5f * (fm - fp) / curv, -0.5f), 0.5f);
      offsets[d] = u;
      gain += 0.5f * (fp - fm) * u + 0.5f * curv * u * u;
    }
  }
  *value = centre + gain;
}

}  // namespace detail

#ifndef PCL_NO_PRECOMPILE
template class BhattacharyaRegistration<pcl::PointXYZ, pcl::PointXYZ, float>;
template class BhattacharyaRegistration<pcl::PointXYZI, pcl::PointXYZI, float>;
template class BhattacharyaRegistration<pcl::PointXYZ, pcl::PointXYZI, float>;
template class BhattacharyaRegistration<pcl::PointXYZI, pcl::PointXYZ, float>;
#endif

}  // namespace pcl_movers
