#include <gtest/gtest.h>

#include <cmath>

#include "solve/reduced_dynamics.h"
#include "test_support.h"

namespace modal_deform {
namespace {

using testing::expect_input_error;

// A rest Hessian with a zero (rigid) eigenvalue and flexible ones 2 and 5.
Eigen::MatrixXd hessian() { return Eigen::Vector3d(0, 2, 5).asDiagonal(); }

TEST(DynamicsParameters, OptionsBeyondDoublePrecisionTogetherAreRefused) {
  SimulationOptions options;
  const DynamicsParameters parameters = dynamics_parameters(hessian(), options);
  EXPECT_GT(parameters.mass_scale, 0);
  EXPECT_DOUBLE_EQ(parameters.substep, 1 / (options.fps * options.substeps));
  // Each within its range: ρ grows as fps⁻², and so does the frame's length squared.
  for (const double fps : {1e-300, 1e-160}) {
    options.fps = fps;
    expect_input_error([&] { dynamics_parameters(hessian(), options); }, "beyond double precision");
  }
  options.fps = 1e-150;
  options.period = 1e6;
  options.damping = 1;
  options.substeps = kMaxSubsteps;
  expect_input_error([&] { dynamics_parameters(hessian(), options); }, "fps = 1e-150, period = ");
  options.fps = 1e-100;
  const DynamicsParameters slow = dynamics_parameters(hessian(), options);
  EXPECT_TRUE(std::isfinite(slow.mass_scale) && slow.mass_scale > 0);
  EXPECT_TRUE(std::isfinite(slow.rayleigh) && std::isfinite(slow.substep * slow.substep));
}

}  // namespace
}  // namespace modal_deform
