#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>
#include <string>

#include "core/settings_checker.hpp"
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

// The checker behind every validate() (src/core/settings_checker.hpp) writes numbers as an ostream with
// precision 12 does, without the stream.
namespace {
std::string streamed(double v) {
  std::ostringstream out;
  out.precision(12);
  out << v;
  return out.str();
}
}  // namespace

TEST(SettingsChecker, WritesNumbersAsAStreamWithPrecisionTwelve) {
  const double values[] = {0.0,     -0.0,       1.0,        -2.5,     0.1,      1.0 / 3.0, 2e-7,
                           123456789012345.0, 1e300,  -1e-300,  5e-324,   0.25,     1e12,      1e11,
                           999999999999.5,    INFINITY, -INFINITY, NAN, 1.7976931348623157e308};
  for (double v : values) {
    occtrack::detail::SettingsChecker c;
    c.require(false, v);
    EXPECT_EQ(c.message(), streamed(v)) << "value " << v;
  }
  occtrack::detail::SettingsChecker c;
  c.require(false, "n (", std::size_t{42}, ") and k (", -7, ") ", std::string("s"), ' ', true, 0.5f);
  EXPECT_EQ(c.message(), "n (42) and k (-7) s 10.5");
}

TEST(SettingsChecker, KeepsTheFirstBrokenRuleInTheStringItWasGiven) {
  std::string sink = "left over";
  occtrack::detail::SettingsChecker c(sink);
  EXPECT_TRUE(c.ok()) << "a given string starts cleared";
  c.require(true, "not this");
  c.positive(-1.0, "first");
  c.finite(NAN, "second");
  EXPECT_FALSE(c.ok());
  EXPECT_EQ(sink, "first must be a positive number, got -1");
  std::string error;
  EXPECT_FALSE(c.done(&error));
  EXPECT_EQ(error, sink);
  EXPECT_FALSE(c.done(&sink)) << "done() into its own string leaves it as it is";
  EXPECT_EQ(sink, "first must be a positive number, got -1");
}
