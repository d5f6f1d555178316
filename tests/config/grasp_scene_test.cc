// tool.grasp (issue 28): read into the tool's GraspOptions, and each scene a grasp cannot run in
// refused at its file, line and key.
#include <gtest/gtest.h>

#include <string>

#include "config/scene.h"
#include "config/simulation_builder.h"
#include "core/error.h"
#include "tests/config/scene_test_support.h"

namespace hapsim::config {
namespace {

using test::ExpectError;
using test::Replace;

constexpr char kLabel[] = "grasp.yaml";
constexpr char kGraspScene[] =
    "name: grasp                                                          #  1\n"
    "time: {dt_s: 0.02, num_steps: 10}                                    #  2\n"
    "body:                                                                #  3\n"
    "  mesh: {box: {min_m: [0, 0, 0], max_m: [0.02, 0.02, 0.02], cells: [2, 2, 2]}}\n"
    "  material: {youngs_modulus_Pa: 8000, poisson_ratio: 0.45, density_kg_m3: 1000}\n"
    "  fixed: {min_m: [-1, -1, -0.001], max_m: [1, 1, 0.001]}            #  6\n"
    "tool:                                                                #  7\n"
    "  shape: {sphere: {radius_m: 0.003}}                                 #  8\n"
    "  mass_kg: 0.02                                                      #  9\n"
    "  grasp: {jaw_center_m: [0, 0, -0.003], jaw_radius_m: 0.004, max_force_N: 1.5}\n"
    "coupling: {k_lin_N_m: 300, b_lin_N_s_m: 2, k_ang_N_m_rad: 0.5, b_ang_N_m_s_rad: 0.005}\n"
    "device:                                                              # 12\n"
    "  trajectory: [{t_s: 0, position_m: [0, 0, 0.03]}]                   # 13\n";

TEST(GraspScene, ReadsTheJaws) {
  const Scene scene = ParseScene(kGraspScene, kLabel, "");
  ASSERT_TRUE(scene.tool && scene.tool->grasp);
  EXPECT_EQ(scene.tool->grasp->jaw_center_T_m, Eigen::Vector3d(0, 0, -0.003));
  EXPECT_EQ(scene.tool->grasp->jaw_radius_m, 0.004);
  EXPECT_EQ(scene.tool->grasp->max_force_N, 1.5);
  ASSERT_TRUE(MakeVisualFrameOptions(scene).grasp.has_value());
  // Without max_force_N the grip never slips.
  const Scene unlimited = ParseScene(Replace(kGraspScene, ", max_force_N: 1.5", ""), kLabel, "");
  EXPECT_TRUE(std::isinf(unlimited.tool->grasp->max_force_N));
}

TEST(GraspScene, BadJawsAreRefusedAtTheirKey) {
  ExpectError(Replace(kGraspScene, "jaw_radius_m: 0.004", "jaw_radius_m: 0"), kLabel, 10,
              "tool.grasp.jaw_radius_m", "> 0");
  ExpectError(Replace(kGraspScene, "max_force_N: 1.5", "max_force_N: -1"), kLabel, 10,
              "tool.grasp.max_force_N", "> 0");
  ExpectError(Replace(kGraspScene, "jaw_center_m: [0, 0, -0.003], ", ""), kLabel, 10,
              "tool.grasp.jaw_center_m", "missing");
  ExpectError(Replace(kGraspScene, "max_force_N: 1.5", "grip_N: 1"), kLabel, 10,
              "tool.grasp.grip_N", "allowed keys here: jaw_center_m, jaw_radius_m, max_force_N");
}

TEST(GraspScene, ScenesAGraspCannotRunInAreRefused) {
  // Friction rows come in threes per contact; a grasp's rows are normal rows.
  ExpectError(std::string(kGraspScene) + "contact: {law: friction, friction_coefficient: 0.3}\n",
              kLabel, 10, "tool.grasp", "contact.law must be unilateral or equality");
  // The geometric modes find their own contacts at 1 kHz.
  ExpectError(std::string(kGraspScene) + "haptic: {mode: penalty}\n", kLabel, 14, "haptic.mode",
              "cannot render a grasp's rows");
  // Nothing to hold.
  std::string no_body = kGraspScene;
  no_body.erase(no_body.find("body:"), no_body.find("tool:") - no_body.find("body:"));
  ExpectError(no_body, kLabel, 6, "tool.grasp", "needs a deformable body");
  // A mode given on the command line is checked as the scene's is.
  const Scene scene = ParseScene(kGraspScene, kLabel, "");
  EXPECT_THROW(ResolveHapticMode(scene, "material", "--mode", false), InputError);
  EXPECT_EQ(ResolveHapticMode(scene, "lcp", "--mode", false), device::HapticMode::kLcp);
}

}  // namespace
}  // namespace hapsim::config
