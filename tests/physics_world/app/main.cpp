// physics-world: one run of the independent tendon-sheath world as a
// recording CSV (docs/data-formats.md) with truth columns, e.g.
//   build/bin/physics-world --world-seed 3 --kind palpation --motion-seed 7 --output run.csv
#include <CLI/CLI.hpp>
#include <cstdio>
#include <exception>
#include <string>

#include "physics_world/recorder.hpp"

int main(int argc, char** argv) {
  using namespace tsmh::physics_world;
  CLI::App app{"Runs the independent tendon-sheath physics world and writes its recording"};
  std::uint64_t world_seed = 1;
  std::string kind_name = "multisine";
  RunConfig run;
  std::string output;
  bool derivatives = false;
  app.add_option("--world-seed", world_seed, "The sheath (friction, stiffness, bends, tip loads)");
  app.add_option("--kind", kind_name, "multisine, surgeon, reversals, creep, palpation or reroute");
  app.add_option("--motion-seed", run.motion_seed, "The motion, tip torque and sensor noise");
  app.add_option("--duration", run.duration_s, "Seconds")->check(CLI::Range(0.01, 3600.0));
  app.add_option("--output", output, "CSV to write")->required();
  app.add_flag("--exact-derivatives", derivatives, "Also write xd_in, xdd_in");
  CLI11_PARSE(app, argc, argv);
  const auto kind = motion_kind_from_name(kind_name);
  if (!kind) {
    std::fprintf(stderr, "physics-world: --kind: unknown motion kind '%s'\n", kind_name.c_str());
    return 2;
  }
  run.kind = *kind;
  try {
    const WorldRecording r = record(random_world(world_seed), run);
    write_csv(r, output, derivatives);
    std::fprintf(stderr,
                 "physics-world: world %llu, %s %llu: %zu samples, wraps %.2f / %.2f rad, mu "
                 "%.3f / %.3f -> %s\n",
                 static_cast<unsigned long long>(world_seed), kind_name.c_str(),
                 static_cast<unsigned long long>(run.motion_seed), r.recording.size(),
                 Tendon(r.world.tendon1, r.world.route1.wrap_rad).total_wrap(),
                 Tendon(r.world.tendon2, r.world.route2.wrap_rad).total_wrap(), r.world.tendon1.mu,
                 r.world.tendon2.mu, output.c_str());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "physics-world: %s\n", e.what());
    return 1;
  }
  return 0;
}
