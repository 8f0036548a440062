/*
 * SPDX-License-Identifier: BSD-3-Clause
 */
#pragma once

#include <pcl_movers/sim/scenario.h>

#include <cstdint>
#include <string>
#include <vector>

namespace pcl_movers {
namespace sim {

/** \brief Settings shared by every generated scene (the scene corpus, docs/design.md). */
struct SceneOptions {
  int frames = 150;       ///< frames per scene: 15 s at 10 Hz
  double rate_hz = 10.0;  ///< frame rate [Hz]
};

/** \brief The scene families: "highway", "urban" (street and junction), "parking", "open"
 * (off-road rolling terrain) and "trail" (forest trail with dense trees and brush). */
const std::vector<std::string>& sceneFamilies();

/** \brief The sensors scenes are recorded with: hdl64, hdl32, vlp16, os1_64, ladar2d. */
const std::vector<std::string>& sceneSensors();

/** \brief The half of the corpus a seed belongs to. Parameters and rules are chosen on the tune
 * half only; the check half is reported and never tuned on. */
enum class Split { kTune, kCheck };

/** \brief Odd seeds tune, even seeds check (seeds start at 1). */
Split splitOf(std::uint64_t seed);
/** \brief "tune" or "check". */
std::string splitName(Split split);

/** \brief The sensor of a seed: seeds 2k-1 and 2k use sceneSensors()[k mod 5], so each pair
 * of seeds (one tune, one check) shares its sensor and ten consecutive seeds hold every sensor in
 * both halves. */
std::string sensorOfSeed(std::uint64_t seed);

/** \brief Draws a whole scene of `family` from `seed`: the sensor (sensorOfSeed) and its mounting
 * height (1.5-2.5 m), range noise, dropout and 1-3 blind frames in half of the scenes; the
 * family's layout (roads, buildings, parked cars, trees, brush); the ego drive; and movers of
 * every class from slow walkers (0.55 m/s) to highway traffic (38 m/s), placed so that each
 * passes near the ego vehicle at a drawn time, with people walking 0.3-0.5 m from walls, parked
 * cars, poles and brush and in groups of 2-3.
 *
 * Every number is rounded to the precision toYaml() prints, so that the YAML of a scene read back
 * by parseScenario() simulates to byte-identical output. The same family and seed always give the
 * same scene. Throws InputError for an unknown family or a seed of 0. */
Scenario generateScene(const std::string& family, std::uint64_t seed,
                       const SceneOptions& options = SceneOptions());

/** \brief The scenario as a plain scenario file (data/scenarios/README.md) that parseScenario()
 * reads back into the same scenario. */
std::string toYaml(const Scenario& scenario);

}  // namespace sim
}  // namespace pcl_movers
