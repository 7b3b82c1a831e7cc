#include <calib/core/scan/scan_simulator.h>
#include <calib/core/scan/self_returns.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

namespace calib {
namespace {

ScanSimOptions Robot() {
  ScanSimOptions o;
  o.laser = DefaultScanLaserOptions();
  o.laser.num_intervals = 300;
  o.beams = 360;
  o.range_noise_sigma_m = 0.01;
  o.missing_probability = 0.02;
  return o;
}

// The mast's posts and the guard are found, each run of beams with a neighbour on either side
// (the edges' beams mix body and wall); nothing else is.
TEST(SelfReturns, TheRobotsOwnBodyIsFoundAndNothingElse) {
  ScanSimOptions o = Robot();
  AddMastAndGuard(&o);
  StatusOr<ScanSimulation> sim = SimulateScans(o);
  ASSERT_TRUE(sim.ok()) << sim.message();
  const SelfReturns self = FindSelfReturns(sim->scans);
  // Beams at −180° + i°: the posts at 130–139° and −140 to −131°, the guard at 170–189°. Every
  // one of them is found, and no beam more than one from them.
  std::vector<int> body;
  for (const int from : {0, 40, 310, 350}) {
    for (int i = from; i < from + 10; ++i) body.push_back(i);
  }
  for (const int i : body) {
    EXPECT_TRUE(std::count(self.beams.begin(), self.beams.end(), i)) << i;
  }
  for (const int i : self.beams) {
    const auto near = [&](int j) { return std::abs(i - j) <= 1 || std::abs(i - j) >= 359; };
    EXPECT_TRUE(std::any_of(body.begin(), body.end(), near)) << i;
  }
  EXPECT_NEAR(self.min_range_m, 0.15, 0.01);
  EXPECT_NEAR(self.max_range_m, 0.25, 0.01);
  ASSERT_EQ(self.sectors_rad.size(), 4u);
  EXPECT_NEAR(self.sectors_rad[2].first * 180.0 / M_PI, 129.0, 1e-9);
  EXPECT_NE(self.Describe(301).find("46 beams (-180° to -170°, -141° to -130°, 129° to 140°, 169° "
                                    "to 179°) return from 0.15–0.25 m in scan after scan of 301"),
            std::string::npos)
      << self.Describe(301);

  MaskBeams(self.beams, &sim->scans);
  EXPECT_FALSE(sim->scans[7].IsReturn(45));
  EXPECT_TRUE(FindSelfReturns(sim->scans).beams.empty());

  for (const char* world : {"rooms", "corridor", "clutter"}) {
    ScanSimOptions plain = Robot();
    plain.world.kind = std::string(world) == "rooms"      ? WorldKind::kRooms
                       : std::string(world) == "corridor" ? WorldKind::kCorridor
                                                          : WorldKind::kClutter;
    const StatusOr<ScanSimulation> clean = SimulateScans(plain);
    ASSERT_TRUE(clean.ok()) << clean.message();
    EXPECT_TRUE(FindSelfReturns(clean->scans).beams.empty()) << world;
  }
}

// A robot that stood still sees every beam stay put: nothing can be told to be its body. Scans
// whose beams differ (count or angles) are not judged.
TEST(SelfReturns, AStillRobotOrUnlikeScansGiveNone) {
  ScanSimOptions o = Robot();
  AddMastAndGuard(&o);
  StatusOr<ScanSimulation> sim = SimulateScans(o);
  ASSERT_TRUE(sim.ok()) << sim.message();
  std::vector<LaserScan> still(50, sim->scans.front());
  EXPECT_TRUE(FindSelfReturns(still).beams.empty());
  sim->scans[100].ranges_m.pop_back();
  EXPECT_TRUE(FindSelfReturns(sim->scans).beams.empty());
}

}  // namespace
}  // namespace calib
