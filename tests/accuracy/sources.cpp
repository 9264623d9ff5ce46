#include "sources.hpp"

#include <algorithm>
#include <stdexcept>

#include "estimator/synthetic.hpp"
#include "estimator/tsm_model.hpp"
#include "physics_world/recorder.hpp"
#include "virtual_tissue_slave/offline.hpp"

namespace tsmh::accuracy {

namespace {

Scored from_world(std::uint64_t world_seed, physics_world::MotionKind kind,
                  std::uint64_t motion_seed, double duration_s) {
  physics_world::RunConfig run;
  run.kind = kind;
  run.motion_seed = motion_seed;
  run.duration_s = duration_s;
  physics_world::WorldRecording w =
      physics_world::record(physics_world::random_world(world_seed), run);
  Scored s;
  s.kind = physics_world::motion_kind_name(kind);
  s.rec = std::move(w.recording);
  s.rec.xd_in.clear();
  s.rec.xdd_in.clear();
  s.friction_true = std::move(w.friction_true);
  s.tau_out_true = std::move(w.tau_out_true);
  s.contact.reserve(w.contact.size());
  for (double c : w.contact)
    s.contact.push_back(c > 0.0 ? 1 : 0);
  return s;
}

// The paper's model through the synthetic generator's sensors. The true tip
// torque comes from a twin run with negligible torque noise: the same seed
// draws the same motion, load and noise sequence (scaled to nothing).
Scored from_paper(estimator::MotionKind kind, std::uint64_t seed, bool from_rest,
                  double duration_s) {
  const estimator::TsmFrictionModel truth(estimator::paper_spec());
  estimator::SyntheticConfig c;
  c.motion = kind;
  c.seed = seed;
  c.from_rest = from_rest;
  c.duration_s = duration_s;
  estimator::SyntheticData data = estimator::make_synthetic(truth, c);
  c.torque_noise = 1e-30;
  const estimator::SyntheticData clean = estimator::make_synthetic(truth, c);
  if (clean.recording.x_in != data.recording.x_in)
    throw std::logic_error("paper source: the noiseless twin moved differently");
  Scored s;
  s.kind = estimator::motion_kind_name(kind);
  s.rec = std::move(data.recording);
  s.friction_true = std::move(data.true_friction);
  s.tau_out_true = clean.recording.tau_out;
  return s;
}

Scored from_slave(const std::string& scenario, std::uint64_t seed, double duration_s) {
  using namespace virtual_tissue_slave;
  const SlaveParams params = paper_slave();
  OfflineOptions o;
  o.scenario = make_scenario(scenario);
  o.duration_s = duration_s;
  o.seed = seed;
  constexpr std::size_t joint = 0;  // the gripper
  const double radius = params.joints[joint].radius_m;
  Scored s;
  s.kind = scenario;
  s.rec.source = "virtual slave offline, " + scenario + " " + std::to_string(seed);
  s.rec.radius_m = radius;
  run_offline(params, o, [&](const SlaveSample& sample) {
    const Measurement& m = sample.measured[joint];
    const JointTruth& t = sample.truth[joint];
    s.rec.t.push_back(sample.t);
    s.rec.x_in.push_back(m.x_in);
    s.rec.T1.push_back(m.T1);
    s.rec.T3.push_back(m.T3);
    s.rec.tau_in.push_back(radius * (m.T1 - m.T3));
    s.rec.x_out.push_back(m.x_out);  // NaN without a joint encoder
    // The slave's recordings carry the true tip torque as tau_out.
    s.rec.tau_out.push_back(t.tau_out);
    s.friction_true.push_back(t.friction);
    s.tau_out_true.push_back(t.tau_out);
    s.contact.push_back(t.contact.force_n > 0.0 ? 1 : 0);
  });
  return s;
}

}  // namespace

std::vector<std::string> source_kinds(const std::string& source) {
  if (source == "world")
    return {"multisine", "surgeon", "reversals", "creep", "palpation", "reroute"};
  if (source == "paper") return {"multisine", "surgeon", "reversals", "creep"};
  if (source == "slave") return {"palpate", "multisine", "sine"};
  throw std::invalid_argument("unknown source '" + source + "' (world, paper or slave)");
}

Set make_set(const std::string& source, std::uint64_t seed, const std::vector<std::string>& kinds,
             double duration_s) {
  const auto known = source_kinds(source);
  Set set;
  set.source = source;
  set.seed = seed;
  for (const auto& k : kinds)
    if (std::find(known.begin(), known.end(), k) == known.end())
      throw std::invalid_argument("source " + source + " has no kind '" + k + "'");
  if (source == "world") {
    // Seed = the sheath; its calibration run and every test run have motion
    // seeds of their own.
    set.calibration =
        from_world(seed, physics_world::MotionKind::kMultisine, seed * 1000, duration_s);
    set.calibration.kind = "calibration (multisine)";
    // A kind's motion seed is its place in the full list, so a recording
    // is the same whichever kinds are asked for.
    for (const auto& k : kinds) {
      const auto place =
          static_cast<std::uint64_t>(std::find(known.begin(), known.end(), k) - known.begin());
      set.tests.push_back(from_world(seed, *physics_world::motion_kind_from_name(k),
                                     seed * 1000 + 1 + place, duration_s));
    }
  } else if (source == "paper") {
    set.calibration = from_paper(estimator::MotionKind::kMultisine, seed, false, duration_s);
    set.calibration.kind = "calibration (multisine)";
    for (const auto& k : kinds)
      set.tests.push_back(
          from_paper(*estimator::motion_kind_from_name(k), seed + 5000, true, duration_s));
  } else {
    set.calibration = from_slave("identify", seed, duration_s);
    set.calibration.kind = "calibration (identify)";
    for (const auto& k : kinds)
      set.tests.push_back(from_slave(k, seed + 5000, duration_s));
  }
  return set;
}

}  // namespace tsmh::accuracy
