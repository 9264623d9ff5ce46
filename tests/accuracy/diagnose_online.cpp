// Where an online tip-torque error comes from, on the physics world: one
// world seed and motion kinds, one model fitted on the calibration run as
// model_accuracy does, then the test runs' estimate taken apart:
//   deployed   the deployed estimator (differentiator, corrections), as scored
//   exact      the same model fed the world's exact xd, xdd (update_exact)
//   oracle     the same model class fitted on the test run itself (its own
//              tip sensor), run deployed: what the structure can reach there
//   floor      the true friction (sensor noise alone)
// and the deployed error's squared sum split by regime: contact / free,
// speed, time since a move started after a hold, the slack tendon.
//
// In holds (the input pulley still for > 50 ms) it also says how far the
// true friction, the distal angle and the model's friction moved from their
// values where the hold began.
//
//   build/bin/diagnose_online --seed S [--kinds k,...] [--model distributed]
//       [--no-oracle] [--trace]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "estimator/distal_estimator.hpp"
#include "estimator/fit_workflow.hpp"
#include "estimator/model_io.hpp"
#include "estimator/tsm_model.hpp"
#include "physics_world/recorder.hpp"
#include "scoring.hpp"
#include "sources.hpp"

namespace {

using namespace tsmh;

struct Regime {
  const char* name;
  double se = 0.0, floor_se = 0.0;
  std::size_t n = 0;
};

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double rms(double se, std::size_t n) {
  return n ? std::sqrt(se / static_cast<double>(n)) : std::numeric_limits<double>::quiet_NaN();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Online error decomposition on the physics world"};
  std::uint64_t seed = 5;
  std::string kinds_text = "surgeon,creep,palpation,reroute";
  std::string model_name = "distributed";
  bool oracle = true;
  bool trace = false;
  app.add_option("--seed", seed);
  app.add_option("--kinds", kinds_text);
  app.add_option("--model", model_name);
  app.add_flag("!--no-oracle", oracle, "Skip the fit on each test run");
  app.add_flag("--trace", trace, "Print samples of holds where the model's friction moved > 2 N");
  CLI11_PARSE(app, argc, argv);
  std::vector<std::string> kinds;
  {
    std::stringstream in(kinds_text);
    std::string k;
    while (std::getline(in, k, ','))
      kinds.push_back(k);
  }
  const auto known = accuracy::source_kinds("world");
  const accuracy::Set set = accuracy::make_set("world", seed, kinds, 40.0);
  estimator::FitWorkflowOptions fo;
  fo.uncertainty = false;
  const auto initial = estimator::load_model(model_name);
  const estimator::FitRun fit = estimator::run_fit(set.calibration.rec, *initial, model_name, fo);
  std::printf("world seed %llu, %s fitted: validation %.4f N\n",
              static_cast<unsigned long long>(seed), model_name.c_str(), fit.validation.rmse);
  for (const auto& n : fit.fit.notes)
    std::printf("  note: %s\n", n.c_str());
  const auto* tsm = dynamic_cast<const estimator::TsmFrictionModel*>(fit.fit.model.get());
  if (tsm && tsm->spec().slip.enabled) {
    const auto& sl = tsm->spec().slip;
    double el = 0.0;
    for (std::size_t k = 0; k < sl.element_count(); ++k)
      el += sl.weight[k];
    std::printf(
        "  slip: %zu elements (%.4g N in all), widths %.3g .. %.3g, smoothing %.4g rad/s, "
        "stribeck %.4g rad/s; coulomb +%.4g / -%.4g N, stribeck %.4g N, viscous %.4g N "
        "s/rad; copies t%d d%d l%d; bouc-wen terms %zu\n",
        sl.element_count(), el, sl.width_min, sl.width_max, sl.smoothing, sl.stribeck_speed,
        sl.weight[estimator::kSlidingIndex], sl.weight[estimator::kSlidingIndex + 1],
        sl.weight[estimator::kSlidingIndex + 2], sl.weight[estimator::kSlidingIndex + 3],
        sl.tension_copies, sl.drive_copies, sl.load_copies, tsm->spec().terms.size());
    if (sl.distal_elements > 0) {
      std::printf("  distal family:");
      for (std::size_t j = 0; j < sl.distal_count(); ++j)
        std::printf(" %.3g N at %.3g rad", sl.weight[estimator::kDistalIndex + j],
                    sl.distal_width(j));
      std::printf("\n");
    }
  }

  for (std::size_t ki = 0; ki < kinds.size(); ++ki) {
    const auto& s = set.tests[ki];
    const auto place = static_cast<std::uint64_t>(std::find(known.begin(), known.end(), kinds[ki]) -
                                                  known.begin());
    // The same run with its exact derivatives.
    physics_world::RunConfig run;
    run.kind = *physics_world::motion_kind_from_name(kinds[ki]);
    run.motion_seed = seed * 1000 + 1 + place;
    const physics_world::WorldRecording w =
        physics_world::record(physics_world::random_world(seed), run);
    const auto& rec = s.rec;
    const double r = rec.radius_m;
    const std::size_t n = rec.size();

    estimator::DistalTorqueEstimator dep(fit.fit.model->clone(), r);
    estimator::DistalTorqueEstimator ex(fit.fit.model->clone(), r);
    std::vector<double> e_dep(n), e_ex(n), e_fl(n), xd_est(n), f_dep(n);
    // The distal angle where the recording has one (a joint encoder), as
    // SLAVE_STATE carries it online.
    const auto x_out = [&](std::size_t i) { return rec.x_out.size() == n ? rec.x_out[i] : kNaN; };
    for (std::size_t i = 0; i < n; ++i) {
      const auto a = dep.update_tensions(rec.t[i], rec.x_in[i], rec.T1[i], rec.T3[i], x_out(i));
      const auto b =
          ex.update_exact(rec.t[i], rec.x_in[i], w.recording.xd_in[i], w.recording.xdd_in[i],
                          rec.tau_in[i], 0.5 * (rec.T1[i] + rec.T3[i]), x_out(i));
      e_dep[i] = a.tau_out_est - s.tau_out_true[i];
      e_ex[i] = b.tau_out_est - s.tau_out_true[i];
      e_fl[i] = rec.tau_in[i] - r * s.friction_true[i] - s.tau_out_true[i];
      xd_est[i] = a.xd;
      f_dep[i] = a.friction;
    }
    std::vector<double> e_or;
    std::string oracle_notes;
    if (oracle) try {
        // The oracle asks less of its data than a calibration: a creep run
        // reverses only slowly.
        estimator::FitWorkflowOptions oo = fo;
        oo.requirements.reversal_speed = 0.002;
        oo.requirements.min_reversals = 1;
        const estimator::FitRun of = estimator::run_fit(rec, *initial, model_name, oo);
        estimator::DistalTorqueEstimator o(of.fit.model->clone(), r);
        e_or.assign(n, 0.0);
        for (std::size_t i = 0; i < n; ++i)
          e_or[i] =
              o.update_tensions(rec.t[i], rec.x_in[i], rec.T1[i], rec.T3[i], x_out(i)).tau_out_est -
              s.tau_out_true[i];
        for (const auto& note : of.fit.notes)
          if (note.find("chosen") != std::string::npos ||
              note.find("hysteresis") != std::string::npos ||
              note.find("distal") != std::string::npos)
            oracle_notes += " [" + note + "]";
      } catch (const std::exception& ex_fit) {
        e_or.clear();
        oracle_notes = std::string(" [no oracle: ") + ex_fit.what() + "]";
      }
    // Regimes by the true motion.
    std::vector<Regime> reg = {{"contact"},
                               {"free"},
                               {"|xd| < 2 mrad/s (rest)"},
                               {"|xd| 2-20 mrad/s"},
                               {"|xd| 20-100 mrad/s"},
                               {"|xd| 0.1-0.5 rad/s"},
                               {"|xd| > 0.5 rad/s"},
                               {"first 100 ms of a move after a hold"},
                               {"hold (|xd| < 2 mrad/s for > 50 ms)"},
                               {"min(T1,T3) < 2 N (slack)"},
                               {"after reroute / t > 20 s"}};
    double peak = 0.0, se_dep = 0, se_ex = 0, se_fl = 0, se_or = 0;
    std::size_t scored = 0;
    double hold_s = 1.0, move_s = 0.0;
    // In holds: how far the true friction and the distal angle move while
    // the input pulley stands still (the model, driven by x_in, cannot).
    double f_hold0 = 0.0, xo_hold0 = 0.0, se_fh = 0.0, se_xo = 0.0, se_em = 0.0;
    double fm_hold0 = 0.0, se_fm = 0.0, se_e0 = 0.0, u_hold0 = 0.0, se_u = 0.0, t_hold0 = 0.0,
           se_t = 0.0;
    std::size_t n_hold = 0;
    int traced = 0;
    const double from = rec.t.front() + accuracy::kWarmUpS;
    for (std::size_t i = 0; i < n; ++i) {
      const double v = std::fabs(w.recording.xd_in[i]);
      const double dt = i ? rec.t[i] - rec.t[i - 1] : 0.001;
      if (v < 2e-3) {
        hold_s += dt;
        if (hold_s > 0.05) move_s = 1e9;
      } else {
        if (hold_s > 0.05) move_s = 0.0;
        hold_s = 0.0;
        move_s += dt;
      }
      if (hold_s > 0.0 && hold_s <= dt + 1e-9) {
        f_hold0 = s.friction_true[i];
        fm_hold0 = f_dep[i];
        u_hold0 = rec.tau_in[i] / r;
        t_hold0 = 0.5 * (rec.T1[i] + rec.T3[i]);
        xo_hold0 = rec.x_out.empty() ? 0.0 : rec.x_out[i];
      }
      if (hold_s > 0.05 && rec.t[i] >= from) {
        const double df = s.friction_true[i] - f_hold0;
        const double dxo = rec.x_out.empty() ? 0.0 : rec.x_out[i] - xo_hold0;
        se_fh += df * df;
        se_xo += dxo * dxo;
        se_em += (e_dep[i] - e_fl[i]) * (e_dep[i] - e_fl[i]);
        se_fm += (f_dep[i] - fm_hold0) * (f_dep[i] - fm_hold0);
        if (trace && std::fabs(f_dep[i] - fm_hold0) > 2.0 && traced < 40 && i % 20 == 0) {
          ++traced;
          std::printf(
              "    t %.3f x_in %.5f xd %.4f T1 %.2f T3 %.2f u %.2f F_model %.3f (hold start "
              "%.3f) F_true %.3f (hold start %.3f) contact %d\n",
              rec.t[i], rec.x_in[i], w.recording.xd_in[i], rec.T1[i], rec.T3[i], rec.tau_in[i] / r,
              f_dep[i], fm_hold0, s.friction_true[i], f_hold0,
              s.contact.empty() ? 0 : s.contact[i]);
        }
        se_e0 += (fm_hold0 - f_hold0) * (fm_hold0 - f_hold0);
        se_u += (rec.tau_in[i] / r - u_hold0) * (rec.tau_in[i] / r - u_hold0);
        const double dT = 0.5 * (rec.T1[i] + rec.T3[i]) - t_hold0;
        se_t += dT * dT;
        ++n_hold;
      }
      if (rec.t[i] < from || !std::isfinite(e_dep[i])) continue;
      peak = std::max(peak, std::fabs(s.tau_out_true[i]));
      ++scored;
      se_dep += e_dep[i] * e_dep[i];
      se_ex += e_ex[i] * e_ex[i];
      se_fl += e_fl[i] * e_fl[i];
      if (!e_or.empty()) se_or += e_or[i] * e_or[i];
      const auto add = [&](std::size_t k) {
        reg[k].se += e_dep[i] * e_dep[i];
        reg[k].floor_se += e_fl[i] * e_fl[i];
        ++reg[k].n;
      };
      add(!s.contact.empty() && s.contact[i] ? 0 : 1);
      add(v < 2e-3 ? 2 : v < 0.02 ? 3 : v < 0.1 ? 4 : v < 0.5 ? 5 : 6);
      if (move_s < 0.1) add(7);
      if (hold_s > 0.05) add(8);
      if (std::min(rec.T1[i], rec.T3[i]) < 2.0) add(9);
      if (rec.t[i] > 20.0) add(10);
    }
    const auto pct = [&](double se) { return 100.0 * rms(se, scored) / peak; };
    std::printf(
        "\n%s (peak %.1f mN m): deployed %.2f %%, exact derivatives %.2f %%, oracle %.2f %%, "
        "floor %.2f %% (ratios %.2f / %.2f / %.2f)%s\n",
        kinds[ki].c_str(), 1e3 * peak, pct(se_dep), pct(se_ex), e_or.empty() ? kNaN : pct(se_or),
        pct(se_fl), std::sqrt(se_dep / se_fl), std::sqrt(se_ex / se_fl),
        e_or.empty() ? kNaN : std::sqrt(se_or / se_fl), oracle_notes.c_str());
    if (n_hold)
      std::printf(
          "  in holds: the true friction moves %.3f N rms from its value at the hold's "
          "start, x_out %.4f rad rms; the model's friction error there %.3f N rms\n",
          rms(se_fh, n_hold), rms(se_xo, n_hold), rms(se_em, n_hold) / r);
    if (n_hold)
      std::printf(
          "  in holds: the model's friction moves %.3f N rms from its hold-start value "
          "(the drive u = tau_in/R %.3f N rms, the mean tension %.3f N rms); its error at the "
          "hold's start %.3f N "
          "rms\n",
          rms(se_fm, n_hold), rms(se_u, n_hold), rms(se_t, n_hold), rms(se_e0, n_hold));
    std::printf("  %-38s %8s %8s %8s %8s\n", "regime", "samples", "share", "rms %", "floor %");
    for (const auto& g : reg) {
      if (g.n == 0) continue;
      std::printf("  %-38s %7.1f%% %7.1f%% %8.2f %8.2f\n", g.name,
                  100.0 * static_cast<double>(g.n) / static_cast<double>(scored),
                  100.0 * g.se / se_dep, 100.0 * rms(g.se, g.n) / peak,
                  100.0 * rms(g.floor_se, g.n) / peak);
    }
  }
  return 0;
}
