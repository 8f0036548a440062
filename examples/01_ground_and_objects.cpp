/*
 * SPDX-License-Identifier: BSD-3-Clause
 *
 * Example 1: one scan → ground removed → objects (the first two stages of the pipeline).
 *
 *   01_ground_and_objects [SCAN.pcd|SCAN.bin]
 *
 * Without an argument it simulates frame 0 of data/scenarios/sample.yaml. An unorganized scan
 * (a KITTI .bin, a plain PCD) is first organized into a range image (rows = beams): the region
 * growing works on the image's angle-depth neighbourhoods, not on a kd-tree. On the bundled scene
 * the program exits with 1 when its result is implausible (it runs as a test).
 */
#include <pcl_movers/ground_plane_filter.h>
#include <pcl_movers/io/sequence.h>
#include <pcl_movers/range_image_organizer.h>
#include <pcl_movers/range_image_region_growing.h>
#include <pcl_movers/sim/lidar_simulator.h>
#include <pcl_movers/sim/scenario.h>

#include <pcl/common/centroid.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

using Point = pcl::PointXYZI;
using Cloud = pcl::PointCloud<Point>;

int main(int argc, char** argv) {
  try {
    Cloud::Ptr scan(new Cloud);
    if (argc > 1) {
      pcl_movers::io::readScan(argv[1], *scan);  // throws InputError naming the file
    } else {
      // The simulator gives an organized HDL-64E scan with ground truth; we only use the scan.
      const auto scenario = pcl_movers::sim::loadScenario(PCL_MOVERS_EXAMPLE_SCENARIO);
      pcl_movers::sim::LidarSimulator simulator(scenario);
      std::vector<std::uint32_t> labels;
      std::vector<pcl_movers::io::GroundTruthObject> truth;
      Eigen::Isometry3d pose;
      simulator.simulate(0, *scan, labels, truth, pose);
    }

    // 1. The range image. Already organized scans pass through unchanged.
    Cloud::Ptr image(new Cloud);
    pcl_movers::RangeImageOrganizer<Point> organizer;
    organizer.setSensorModel(pcl_movers::SensorModel::hdl64());
    organizer.setInputCloud(scan);
    organizer.organize(*image);

    // 2. Ground: a plane per polar cell, each seeded by its inner neighbour (a pcl::FilterIndices:
    //    filter() keeps what is not ground; setNegative(true) would keep the ground instead).
    pcl_movers::GroundPlaneFilter<Point> ground;
    ground.setInputCloud(image);
    pcl::IndicesPtr objects(new pcl::Indices);
    ground.filter(*objects);

    // 3. Objects: 8-neighbours in the image joined when their depths differ by < k · range.
    pcl_movers::RangeImageRegionGrowing<Point> growing;
    growing.setInputCloud(image);
    growing.setIndices(objects);  // chained through indices: no copy of the cloud
    growing.setDepthThresholdFactor(0.03f);
    growing.setMinClusterSize(10);
    std::vector<pcl::PointIndices> clusters;
    growing.segment(clusters);

    std::size_t finite = 0;
    for (const auto& p : *image) finite += std::isfinite(p.x) ? 1 : 0;
    std::printf("scan: %zu points, range image %u x %u (%zu returns)\n", scan->size(),
                image->height, image->width, finite);
    std::printf("ground: %zu points, objects: %zu points\n", finite - objects->size(),
                objects->size());
    std::printf("clusters: %zu (>= 10 points), largest first:\n", clusters.size());
    for (std::size_t c = 0; c < std::min<std::size_t>(clusters.size(), 8); ++c) {
      Eigen::Vector4f centroid;
      pcl::compute3DCentroid(*image, clusters[c].indices, centroid);
      std::printf("  %5zu points at (%6.1f, %6.1f, %5.1f) m, %5.1f m away\n",
                  clusters[c].indices.size(), centroid.x(), centroid.y(), centroid.z(),
                  centroid.head<2>().norm());
    }
    // On the bundled scene (no argument) the program checks its own result, so that the test
    // running it fails when a stage breaks: most returns there are road and terrain, and the
    // cars, people, trees and pole are separate objects.
    if (argc > 1) return 0;
    const bool ok = finite - objects->size() > finite / 2 && clusters.size() >= 5;
    if (!ok) std::fprintf(stderr, "error: unexpected result on the bundled scene\n");
    return ok ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
