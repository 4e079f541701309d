#include <gtest/gtest.h>

#include <cstring>

#include "occtrack/projection/settings.hpp"

using occtrack::projection::Settings;

TEST(Settings, DefaultsAreTheSpecTable) {
  const Settings s;
  EXPECT_EQ(s.degree, 10);
  EXPECT_EQ(s.coefficients(), 11);
  EXPECT_EQ(s.steps, 100);
  EXPECT_EQ(s.horizon, 5.0);
  EXPECT_EQ(s.iterations, 50);
  EXPECT_EQ(s.batch, 30);
  EXPECT_EQ(s.obstacles, 60);
  EXPECT_EQ(s.obstacle_radius, 0.4);
  EXPECT_EQ(s.speed_min, 0.1);
  EXPECT_EQ(s.speed_max, 2.0);
  EXPECT_EQ(s.accel_max, 2.0);
  EXPECT_EQ(s.via_step_1, 49);
  EXPECT_EQ(s.via_step_2, 74);
  EXPECT_EQ(s.rho.obstacle, 1.0);
  EXPECT_EQ(s.rho.velocity, 1.0);
  EXPECT_EQ(s.rho.acceleration, 1.0);
  EXPECT_EQ(s.rho.tracking, 1.0);
  EXPECT_EQ(s.rho.projection, 1.0);
  std::string error;
  EXPECT_TRUE(s.validate(&error)) << error;
}
