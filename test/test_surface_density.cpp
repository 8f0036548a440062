/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#include <pcl_movers/surface_density.h>

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

using pcl_movers::SurfaceDensity;

namespace {

/** Points on the two visible faces of a 4 × 1.8 × 1.5 m box, seen from the origin side. */
pcl::PointCloud<pcl::PointXYZ> boxSurface(const Eigen::Vector3f& centre, unsigned seed,
                                          int n = 400) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-0.5f, 0.5f);
  pcl::PointCloud<pcl::PointXYZ> cloud;
  for (int i = 0; i < n; ++i) {
    if (i % 2 == 0)  // face towards -x
      cloud.push_back(
          pcl::PointXYZ(centre.x() - 0.9f, centre.y() + 4.f * u(rng), centre.z() + 1.5f * u(rng)));
    else  // face towards -y
      cloud.push_back(
          pcl::PointXYZ(centre.x() + 1.8f * u(rng), centre.y() - 2.f, centre.z() + 1.5f * u(rng)));
  }
  return cloud;
}

}  // namespace

TEST(SurfaceDensity, SumsToOneInsideAndLosesMassOutside) {
  SurfaceDensity d;  // 29 × 29 × 7, 0.2 / 0.4 m
  const Eigen::Vector3f centre(20.f, 3.f, 1.f);
  d.compute(boxSurface(centre, 1), Eigen::Vector3f::Zero(), centre);
  EXPECT_NEAR(d.totalMass(), 1.f, 1e-3f);
  for (float v : d.values()) EXPECT_GE(v, 0.f);

  // The same object with the grid centred 3 m away: part of the mass falls outside.
  SurfaceDensity off;
  off.compute(boxSurface(centre, 1), Eigen::Vector3f::Zero(), centre + Eigen::Vector3f(3, 0, 0));
  EXPECT_LT(off.totalMass(), 0.9f);
  EXPECT_GT(off.totalMass(), 0.05f);
}

TEST(SurfaceDensity, SingleGaussianIsCentredAndHasRangeProportionalWidth) {
  // One point exactly at a cell centre: the density is symmetric around that cell; the spread
  // grows with range (σ = sigma_per_metre · range).
  SurfaceDensity near_d(31, 31, 7, 0.1f, 0.4f), far_d(31, 31, 7, 0.1f, 0.4f);
  near_d.setMinSigma(0.01f);
  far_d.setMinSigma(0.01f);
  near_d.setSigmaPerMetre(0.01f);
  far_d.setSigmaPerMetre(0.01f);
  pcl::PointCloud<pcl::PointXYZ> one;
  one.push_back(pcl::PointXYZ(10.f, 0.f, 0.f));
  near_d.compute(one, Eigen::Vector3f::Zero(), Eigen::Vector3f(10.f, 0.f, 0.f));
  pcl::PointCloud<pcl::PointXYZ> one_far;
  one_far.push_back(pcl::PointXYZ(30.f, 0.f, 0.f));
  far_d.compute(one_far, Eigen::Vector3f::Zero(), Eigen::Vector3f(30.f, 0.f, 0.f));
  EXPECT_FLOAT_EQ(near_d.sigmaAtRange(10.f), 0.1f);
  EXPECT_FLOAT_EQ(far_d.sigmaAtRange(30.f), 0.3f);
  // Peak at the middle cell, symmetric neighbours.
  EXPECT_NEAR(near_d.at(14, 15, 3), near_d.at(16, 15, 3), 1e-5f);
  EXPECT_GT(near_d.at(15, 15, 3), near_d.at(14, 15, 3));
  // Wider Gaussian: lower peak, more mass away from the centre.
  EXPECT_GT(near_d.at(15, 15, 3), 3.f * far_d.at(15, 15, 3));
  EXPECT_GT(far_d.at(20, 15, 3), near_d.at(20, 15, 3));
  // Second moment along x matches σ² (cell integration adds ≈ cell²/12).
  double m2 = 0.0, m = 0.0;
  for (int ix = 0; ix < 31; ++ix)
    for (int iy = 0; iy < 31; ++iy)
      for (int iz = 0; iz < 7; ++iz) {
        const double x = (ix - 15) * 0.1;
        m += far_d.at(ix, iy, iz);
        m2 += far_d.at(ix, iy, iz) * x * x;
      }
  EXPECT_NEAR(std::sqrt(m2 / m), std::sqrt(0.09 + 0.01 / 12.0), 0.02);
}

TEST(SurfaceDensity, SqrtAndBhattacharyya) {
  SurfaceDensity a, b, c;
  const Eigen::Vector3f centre(15.f, -2.f, 0.5f);
  a.compute(boxSurface(centre, 1), Eigen::Vector3f::Zero(), centre);
  b.compute(boxSurface(centre, 1), Eigen::Vector3f::Zero(), centre);
  for (std::size_t i = 0; i < a.size(); ++i)
    ASSERT_NEAR(a.sqrtValues()[i] * a.sqrtValues()[i], a.values()[i], 1e-6f);
  EXPECT_NEAR(SurfaceDensity::bhattacharyya(a, b), 1.f, 1e-3f);
  // A different sampling of the same surface is still very similar; the surface moved by 0.6 m
  // much less so.
  c.compute(boxSurface(centre, 2), Eigen::Vector3f::Zero(), centre);
  EXPECT_GT(SurfaceDensity::bhattacharyya(a, c), 0.9f);
  SurfaceDensity moved;
  moved.compute(boxSurface(centre + Eigen::Vector3f(0.6f, 0.f, 0.f), 1), Eigen::Vector3f::Zero(),
                centre);
  EXPECT_LT(SurfaceDensity::bhattacharyya(a, moved), 0.8f);
}

TEST(SurfaceDensity, NaNPointsAndEmptyClouds) {
  SurfaceDensity d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  d.compute(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero());
  EXPECT_TRUE(d.empty());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  cloud.push_back(pcl::PointXYZ(nan, 0.f, 0.f));
  cloud.push_back(pcl::PointXYZ(0.f, std::numeric_limits<float>::infinity(), 0.f));
  d.compute(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero());
  EXPECT_TRUE(d.empty());
  cloud.push_back(pcl::PointXYZ(0.2f, 0.f, 0.f));
  d.compute(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f::Zero());
  EXPECT_NEAR(d.totalMass(), 1.f, 1e-3f);  // the only valid point carries all the mass
}

TEST(SurfaceDensity, AccumulateWithHalfLife) {
  EXPECT_NEAR(SurfaceDensity::halfLifeWeight(1.f), 0.5f, 1e-6f);
  const float w = SurfaceDensity::halfLifeWeight(3.f);
  EXPECT_NEAR(std::pow(1.f - w, 3.f), 0.5f, 1e-5f);

  const Eigen::Vector3f centre(20.f, 0.f, 0.f);
  SurfaceDensity model, a, b;
  a.compute(boxSurface(centre, 1), Eigen::Vector3f::Zero(), centre);
  b.compute(boxSurface(centre + Eigen::Vector3f(0.8f, 0.f, 0.f), 3), Eigen::Vector3f::Zero(),
            centre);
  model = SurfaceDensity();
  model.setCentre(centre);
  model.accumulate(a, w);  // empty model takes the first view whole
  EXPECT_NEAR(SurfaceDensity::bhattacharyya(model, a), 1.f, 1e-3f);
  // After 3 views of b, a's weight has halved: the mixture is 50/50.
  for (int i = 0; i < 3; ++i) model.accumulate(b, w);
  for (std::size_t i = 0; i < model.size(); i += 37)
    EXPECT_NEAR(model.values()[i], 0.5f * (a.values()[i] + b.values()[i]), 1e-5f);
  EXPECT_NEAR(model.totalMass(), 1.f, 2e-3f);

  SurfaceDensity other_size(9, 9, 3, 0.2f, 0.4f);
  EXPECT_THROW(model.accumulate(other_size, 0.5f), std::invalid_argument);
}

TEST(SurfaceDensity, TranslateAndShift) {
  const Eigen::Vector3f centre(20.f, 0.f, 0.f);
  SurfaceDensity a, b;
  a.compute(boxSurface(centre, 1), Eigen::Vector3f::Zero(), centre);
  // Whole-cell shift: exactly the density of the moved object (on the same grid).
  b.compute(boxSurface(centre + Eigen::Vector3f(0.4f, -0.2f, 0.f), 1), Eigen::Vector3f::Zero(),
            centre);
  const SurfaceDensity s = a.shifted(Eigen::Vector3f(0.4f, -0.2f, 0.f));
  EXPECT_GT(SurfaceDensity::bhattacharyya(s, b), 0.999f);
  EXPECT_EQ(s.getCentre(), a.getCentre());
  // Fractional shift: close, slightly blurred.
  SurfaceDensity c;
  c.compute(boxSurface(centre + Eigen::Vector3f(0.1f, 0.f, 0.f), 1), Eigen::Vector3f::Zero(),
            centre);
  EXPECT_GT(SurfaceDensity::bhattacharyya(a.shifted(Eigen::Vector3f(0.1f, 0.f, 0.f)), c), 0.98f);
  EXPECT_LT(SurfaceDensity::bhattacharyya(a, c),
            SurfaceDensity::bhattacharyya(a.shifted(Eigen::Vector3f(0.1f, 0.f, 0.f)), c));
  // translate() moves the grid with the content: values unchanged, centre moved.
  SurfaceDensity t = a;
  t.translate(Eigen::Vector3f(1.f, 2.f, 0.f));
  EXPECT_EQ(t.values(), a.values());
  EXPECT_TRUE(t.getCentre().isApprox(centre + Eigen::Vector3f(1.f, 2.f, 0.f)));
  // accumulate() of a view on a displaced grid resamples it into place.
  SurfaceDensity model = a;
  SurfaceDensity view_displaced = b;                   // b lives on a grid at `centre`
  model.translate(Eigen::Vector3f(0.4f, -0.2f, 0.f));  // model grid now where b's content is
  SurfaceDensity expected = a;
  model.accumulate(view_displaced, 1.f);  // take the view only, resampled onto the model grid
  // b's content seen from the moved grid equals a's content (a moved by the same offset).
  EXPECT_GT(SurfaceDensity::bhattacharyya(model,
                                          [&] {
                                            SurfaceDensity e = expected;
                                            e.translate(Eigen::Vector3f(0.4f, -0.2f, 0.f));
                                            return e;
                                          }()),
            0.95f);
}

TEST(SurfaceDensity, RevisionFollowsTheContent) {
  pcl_movers::SurfaceDensity d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(10.f, 0.f, 1.f));
  d.compute(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f(10.f, 0.f, 1.f));
  const std::uint64_t r0 = d.revision();
  const pcl_movers::SurfaceDensity copy = d;
  EXPECT_EQ(copy.revision(), r0);  // same content
  d.translate(Eigen::Vector3f(1.f, 0.f, 0.f));
  EXPECT_EQ(d.revision(), r0);  // the grid moved, the values did not
  d.accumulate(copy, 0.5f);
  const std::uint64_t r1 = d.revision();
  EXPECT_NE(r1, r0);
  d.clear();
  EXPECT_NE(d.revision(), r1);
  EXPECT_NE(d.shifted(Eigen::Vector3f(0.1f, 0.f, 0.f)).revision(), copy.revision());
}

// Regression (fuzz_pcd_pipeline, test/fuzz/corpus_pcd/regression_surface_density_huge_window.pcd):
// a point ~1e16 m from the sensor has a σ whose ±3σ window no int can index, and a huge shift
// overflowed the cell offset. Both must simply leave no mass in the grid, without UB or a huge
// allocation, while a normal point beside them keeps its full mass.
TEST(SurfaceDensity, FarPointsAndHugeShiftsLeaveNoMassWithoutOverflow) {
  SurfaceDensity d;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.push_back(pcl::PointXYZ(4e16f, -3e16f, 1e15f));
  d.compute(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f(10.f, 0.f, 0.f));
  EXPECT_TRUE(d.empty());
  cloud.push_back(pcl::PointXYZ(10.f, 0.f, 0.f));
  d.compute(cloud, Eigen::Vector3f::Zero(), Eigen::Vector3f(10.f, 0.f, 0.f));
  EXPECT_NEAR(d.totalMass(), 0.5f, 1e-3f);  // one of the two Gaussians (mass 1/2 each) is inside
  const SurfaceDensity far = d.shifted(Eigen::Vector3f(3e16f, 0.f, 0.f));
  EXPECT_TRUE(far.empty());
  const SurfaceDensity nan_shift =
      d.shifted(Eigen::Vector3f(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f));
  EXPECT_TRUE(nan_shift.empty());
  EXPECT_NEAR(d.shifted(Eigen::Vector3f(0.2f, 0.f, 0.f)).totalMass(), 0.5f, 1e-3f);
}

TEST(SurfaceDensity, MergedGaussiansKeepMassMomentsAndTheDensity) {
  // 2000 points on a box 8 m away, σ = 0.1 m (min σ): several points per σ-cube.
  const Eigen::Vector3f centre(8.f, 1.f, 1.f);
  const auto cloud = boxSurface(centre, 3, 2000);
  std::vector<Eigen::Vector3f> pts;
  std::vector<float> sig;
  for (const auto& p : cloud) {
    pts.emplace_back(p.x, p.y, p.z);
    sig.push_back(0.1f);
  }
  pts.emplace_back(std::numeric_limits<float>::quiet_NaN(), 0.f, 0.f);  // dropped
  sig.push_back(0.1f);
  std::vector<Eigen::Vector3f> mp;
  std::vector<float> sxy, sz, w;
  SurfaceDensity::mergeGaussians(pts, sig, 0.1f, mp, sxy, sz, w);
  ASSERT_EQ(mp.size(), sxy.size());
  ASSERT_EQ(mp.size(), w.size());
  EXPECT_LT(mp.size(), pts.size() / 2);  // it does merge (~20 points per m² of a face)
  // Total weight, mean and second moments (per axis, σ² included) are those of the points.
  double n = 0;
  Eigen::Vector3d mean_m = Eigen::Vector3d::Zero(), mean_p = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < mp.size(); ++i) {
    n += w[i];
    mean_m += w[i] * mp[i].cast<double>();
  }
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) mean_p += pts[i].cast<double>();
  EXPECT_DOUBLE_EQ(n, 2000.0);
  mean_m /= n;
  mean_p /= 2000.0;
  EXPECT_LT((mean_m - mean_p).norm(), 1e-4);
  Eigen::Vector3d m2_m = Eigen::Vector3d::Zero(), m2_p = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < mp.size(); ++i) {
    const Eigen::Vector3d d = mp[i].cast<double>() - mean_p;
    m2_m += w[i] * Eigen::Vector3d(d.x() * d.x() + sxy[i] * sxy[i], d.y() * d.y() + sxy[i] * sxy[i],
                                   d.z() * d.z() + sz[i] * sz[i]);
  }
  for (std::size_t i = 0; i + 1 < pts.size(); ++i) {
    const Eigen::Vector3d d = pts[i].cast<double>() - mean_p;
    m2_p += d.cwiseProduct(d) + Eigen::Vector3d::Constant(0.01);
  }
  // x/y: the merged σ_xy is isotropic, so only the sum over x and y is kept exactly.
  EXPECT_NEAR((m2_m.x() + m2_m.y()) / n, (m2_p.x() + m2_p.y()) / 2000.0, 1e-3);
  EXPECT_NEAR(m2_m.z() / n, m2_p.z() / 2000.0, 1e-3);

  // The densities on the registration's grid (0.2 m cells) are nearly identical.
  SurfaceDensity exact(29, 29, 3, 0.2f, 0.93f), merged(29, 29, 3, 0.2f, 0.93f);
  exact.computeFromPoints(pts, sig, centre);
  merged.computeFromGaussians(mp, sxy, sz, w, centre);
  EXPECT_NEAR(merged.totalMass(), exact.totalMass(), 1e-4f);
  double l1 = 0.0;
  for (std::size_t i = 0; i < exact.size(); ++i)
    l1 += std::abs(exact.values()[i] - merged.values()[i]);
  EXPECT_LT(l1, 0.02);  // ≤ 1 % of the mass moved (L1 of two unit masses is ≤ 2)
  EXPECT_GT(SurfaceDensity::bhattacharyya(exact, merged), 0.999f);

  // cell ≤ 0: the points as they are (weight 1, σ unchanged), invalid ones dropped.
  SurfaceDensity::mergeGaussians(pts, sig, 0.f, mp, sxy, sz, w);
  ASSERT_EQ(mp.size(), 2000u);
  EXPECT_EQ(mp[5], pts[5]);
  EXPECT_EQ(w[5], 1.f);
  EXPECT_EQ(sz[5], 0.1f);
  SurfaceDensity copy(29, 29, 3, 0.2f, 0.93f);
  copy.computeFromGaussians(mp, sxy, sz, w, centre);
  EXPECT_EQ(copy.values(), exact.values());
}

TEST(SurfaceDensity, MassAndSquareRootsFollowEveryChange) {
  // totalMass() is kept with the values: check it after each kind of change.
  const Eigen::Vector3f centre(12.f, -2.f, 1.f);
  SurfaceDensity d;
  EXPECT_EQ(d.totalMass(), 0.f);
  d.compute(boxSurface(centre, 5), Eigen::Vector3f::Zero(), centre);
  auto sum = [](const SurfaceDensity& s) {
    double m = 0.0;
    for (float v : s.values()) m += v;
    return static_cast<float>(m);
  };
  EXPECT_NEAR(d.totalMass(), 1.f, 1e-3f);
  EXPECT_FLOAT_EQ(d.totalMass(), sum(d));
  const SurfaceDensity copy = d;
  EXPECT_FLOAT_EQ(copy.totalMass(), d.totalMass());
  // Moved out entirely: no mass and no square roots left.
  const SurfaceDensity gone = d.shifted(Eigen::Vector3f(100.f, 0.f, 0.f));
  EXPECT_EQ(gone.totalMass(), 0.f);
  for (float v : gone.sqrtValues()) ASSERT_EQ(v, 0.f);
  const SurfaceDensity half = d.shifted(Eigen::Vector3f(2.9f, 0.f, 0.f));
  EXPECT_FLOAT_EQ(half.totalMass(), sum(half));
  EXPECT_LT(half.totalMass(), 0.9f);
  std::vector<float> values(d.size(), 0.f);
  values[7] = 0.25f;
  d.setValues(values);
  EXPECT_FLOAT_EQ(d.totalMass(), 0.25f);
  d.clear();
  EXPECT_EQ(d.totalMass(), 0.f);
  EXPECT_TRUE(d.empty());
  d.setGridSize(5, 5, 5);
  EXPECT_TRUE(d.empty());
}

TEST(SurfaceDensity, CellWeightsMatchErfReferenceInsideClippedAndWideWindows) {
  // The cell weights of one Gaussian are products of 1D cell integrals renormalised over the
  // ±3σ window (before clipping to the grid). Checked against std::erf in double for a Gaussian
  // inside the grid, windows clipped at the low and the high end, and a window wider than 128
  // cells (the per-axis weights then live on the heap).
  auto reference = [](double mean, double sigma, double origin, double cell, int n, int i) {
    const double u = (mean - origin) / cell, reach = 3.0 * sigma / cell;
    const double lo = std::floor(u - reach), hi = std::floor(u + reach);
    if (i < lo || i > hi || i < 0 || i >= n) return 0.0;
    const double s = std::sqrt(2.0) * sigma;
    const double total =
        std::erf(((hi + 1) * cell + origin - mean) / s) - std::erf((lo * cell + origin - mean) / s);
    return (std::erf(((i + 1) * cell + origin - mean) / s) -
            std::erf((i * cell + origin - mean) / s)) /
           total;
  };
  struct Case {
    int nx, ny, nz;
    float res, res_z, sigma_xy, sigma_z;
    Eigen::Vector3f point;
  };
  const Case cases[] = {
      {29, 29, 7, 0.2f, 0.4f, 0.13f, 0.21f, Eigen::Vector3f(0.037f, -0.061f, 0.11f)},  // inside
      {29, 29, 7, 0.2f, 0.4f, 0.13f, 0.21f, Eigen::Vector3f(-2.85f, 2.83f, -1.35f)},   // clipped
      {29, 29, 7, 0.2f, 0.4f, 0.3f, 0.5f, Eigen::Vector3f(2.87f, -2.93f, 1.37f)},      // clipped
      {300, 3, 1, 0.1f, 0.4f, 2.5f, 0.3f, Eigen::Vector3f(0.31f, 0.f, 0.f)},           // wide
      // Windows of 7 and 8 cells: the last one the rasteriser keeps in registers and the first
      // one it builds in memory.
      {29, 29, 7, 0.2f, 0.4f, 0.2f, 0.21f, Eigen::Vector3f(0.013f, 0.029f, 0.11f)},
      {29, 29, 7, 0.2f, 0.4f, 0.23f, 0.21f, Eigen::Vector3f(0.071f, -0.047f, 0.11f)},
  };
  for (const Case& c : cases) {
    SurfaceDensity d(c.nx, c.ny, c.nz, c.res, c.res_z);
    d.computeFromGaussians({c.point}, {c.sigma_xy}, {c.sigma_z}, {}, Eigen::Vector3f::Zero());
    const double ox = -0.5 * c.nx * c.res, oy = -0.5 * c.ny * c.res, oz = -0.5 * c.nz * c.res_z;
    double max_err = 0.0, mass = 0.0;
    for (int iz = 0; iz < c.nz; ++iz)
      for (int iy = 0; iy < c.ny; ++iy)
        for (int ix = 0; ix < c.nx; ++ix) {
          const double ref = reference(c.point.x(), c.sigma_xy, ox, c.res, c.nx, ix) *
                             reference(c.point.y(), c.sigma_xy, oy, c.res, c.ny, iy) *
                             reference(c.point.z(), c.sigma_z, oz, c.res_z, c.nz, iz);
          max_err = std::max(max_err, std::abs(d.at(ix, iy, iz) - ref));
          mass += ref;
        }
    EXPECT_LT(max_err, 2e-6) << "point " << c.point.transpose();
    EXPECT_NEAR(d.totalMass(), mass, 1e-5);
    EXPECT_GT(mass, 0.01);
    // The square roots (taken four at a time) are the correctly rounded ones.
    for (std::size_t i = 0; i < d.size(); ++i)
      ASSERT_EQ(d.sqrtValues()[i], std::sqrt(d.values()[i])) << i;
  }
}

TEST(SurfaceDensity, PreparedGaussiansMatchComputeFromGaussians) {
  // computeFromPrepared() (vertical weights computed once, horizontal positions per call) gives
  // computeFromGaussians()'s density up to float rounding, for grids on the prepared lattice and
  // Gaussians moved horizontally after the preparation, including clipped and missing ones.
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-2.5f, 2.5f), s(0.08f, 0.4f), wt(1.f, 5.f);
  std::vector<Eigen::Vector3f> pts;
  std::vector<float> sxy, sz, w;
  for (int i = 0; i < 300; ++i) {
    pts.emplace_back(u(rng), u(rng), 0.5f * u(rng));
    sxy.push_back(s(rng));
    sz.push_back(s(rng));
    w.push_back(wt(rng));
  }
  pts.emplace_back(40.f, 0.f, 0.f);  // misses every grid below
  sxy.push_back(0.1f);
  sz.push_back(0.1f);
  w.push_back(1.f);
  const float res = 0.2f, res_z = 0.93f;
  // Lattice: cell 0 of a 29 × 29 × 3 grid centred at the origin; prepared for 2 extra cells.
  const float z0 = -1.5f * res_z;
  SurfaceDensity::PreparedGaussians prepared;
  SurfaceDensity::prepareGaussians(pts, sxy, sz, w, res, res_z, z0, -2, 4, prepared);
  EXPECT_EQ(prepared.index.size(), pts.size());  // the far one has vertical weights
  const Eigen::Vector3f shift(0.37f, -0.113f, 0.f);
  std::vector<Eigen::Vector3f> moved = pts;
  for (auto& p : moved) p += shift;
  for (const Eigen::Vector3f centre :
       {Eigen::Vector3f(0.f, 0.f, 0.f), Eigen::Vector3f(0.3f, -0.5f, res_z)}) {
    SurfaceDensity a(29, 29, 3, res, res_z), b(29, 29, 3, res, res_z);
    a.computeFromGaussians(moved, sxy, sz, w, centre);
    // z of the points is ignored: scramble it.
    std::vector<Eigen::Vector3f> flat = moved;
    for (auto& p : flat) p.z() = 100.f;
    b.computeFromPrepared(prepared, flat, centre);
    double max_err = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i)
      max_err = std::max(max_err, static_cast<double>(std::abs(a.values()[i] - b.values()[i])));
    EXPECT_LT(max_err, 1e-6) << centre.transpose();
    EXPECT_NEAR(a.totalMass(), b.totalMass(), 1e-5f);
    EXPECT_GT(a.totalMass(), 0.5f);
  }
  SurfaceDensity other(29, 29, 3, 0.25f, res_z);
  EXPECT_THROW(other.computeFromPrepared(prepared, moved, Eigen::Vector3f::Zero()),
               std::invalid_argument);
}
