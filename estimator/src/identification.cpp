#include "estimator/identification.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <nlopt.hpp>
#include <random>
#include <stdexcept>
#include <thread>

#include "estimator/parameter_map.hpp"
#include "estimator/simulate.hpp"
#include "estimator/tsm_model.hpp"

namespace tsmh::estimator {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The data one stage scores: motion, measured friction, 0/1 weights.
struct Scored {
  std::vector<Motion> motion;
  std::vector<double> measured;
  std::vector<double> weight;
};

Scored full_rate(const FitData& d) {
  return {d.motion, d.measured, d.weights(SampleRole::train)};
}

// Every k-th sample, k chosen for the requested period. The model integrates
// over the actual intervals (Motion::t), so decimation only coarsens its
// step; the polish on full-rate data removes the small bias this causes.
Scored decimated(const FitData& d, double period) {
  if (!(period > 0.0) || d.size() < 2) return full_rate(d);
  const double dt = d.duration() / static_cast<double>(d.size() - 1);
  const auto k = static_cast<std::size_t>(std::max(1.0, std::round(period / dt)));
  Scored s;
  for (std::size_t i = 0; i < d.size(); i += k) {
    s.motion.push_back(d.motion[i]);
    s.measured.push_back(d.measured[i]);
    s.weight.push_back(d.role[i] == SampleRole::train ? 1.0 : 0.0);
  }
  return s;
}

// Shared between the workers and the progress reporter.
struct SharedProgress {
  std::atomic<long> evaluations{0};
  std::atomic<int> starts_done{0};
  std::atomic<double> best_mse{std::numeric_limits<double>::infinity()};
  std::atomic<int> in_local{0};

  void offer(double mse) {
    double cur = best_mse.load(std::memory_order_relaxed);
    while (mse < cur && !best_mse.compare_exchange_weak(cur, mse, std::memory_order_relaxed)) {
    }
  }
};

// One worker's objective: owns its model clone and buffers, so evaluations
// on different threads share nothing but read-only data and the counters.
class Objective {
 public:
  Objective(const FrictionModel& proto, const ParameterMap& map, SharedProgress& shared)
      : model_(proto.clone()), map_(map), shared_(shared) {}

  void use(const Scored& data) {
    data_ = &data;
    buffer_.resize(data.motion.size());
    best_ = std::numeric_limits<double>::infinity();
    best_u_.clear();
  }

  double operator()(const double* u) {
    ++evaluations_;
    shared_.evaluations.fetch_add(1, std::memory_order_relaxed);
    map_.to_values(std::span<const double>(u, map_.size()), values_);
    try {
      model_->set_values(values_);
    } catch (const std::invalid_argument&) {
      return 1e30;  // outside what the model accepts (bounds should prevent it)
    }
    simulate_friction_into(*model_, data_->motion, buffer_);
    double mse = weighted_mse(data_->measured, buffer_, data_->weight);
    if (!std::isfinite(mse)) mse = 1e30;
    if (mse < best_) {
      best_ = mse;
      best_u_.assign(u, u + map_.size());
      if (data_->motion.size() == full_size_) shared_.offer(mse);
    }
    return mse;
  }

  static double call(unsigned n, const double* u, double* grad, void* self) {
    (void)n;
    (void)grad;  // derivative-free algorithms only
    return (*static_cast<Objective*>(self))(u);
  }

  void set_full_size(std::size_t n) { full_size_ = n; }
  double best() const { return best_; }
  const std::vector<double>& best_u() const { return best_u_; }
  long evaluations() const { return evaluations_; }

 private:
  std::unique_ptr<FrictionModel> model_;
  const ParameterMap& map_;
  SharedProgress& shared_;
  const Scored* data_ = nullptr;
  std::vector<double> buffer_, values_, best_u_;
  double best_ = std::numeric_limits<double>::infinity();
  long evaluations_ = 0;
  std::size_t full_size_ = 0;
};

std::string stop_reason(nlopt::result r) {
  switch (r) {
    case nlopt::SUCCESS:
      return "success";
    case nlopt::STOPVAL_REACHED:
      return "target cost reached";
    case nlopt::FTOL_REACHED:
      return "cost converged";
    case nlopt::XTOL_REACHED:
      return "parameters converged";
    case nlopt::MAXEVAL_REACHED:
      return "evaluation budget used";
    case nlopt::MAXTIME_REACHED:
      return "time budget used";
    case nlopt::ROUNDOFF_LIMITED:
      return "round-off limited";
    default:
      return "stopped (" + std::to_string(static_cast<int>(r)) + ")";
  }
}

// Runs one NLopt optimisation; NLopt reports some endings (round-off) as
// exceptions although the best point so far is valid, so the objective's own
// record of its best point is what counts.
std::string run_nlopt(nlopt::opt& opt, Objective& obj, std::vector<double>& u) {
  opt.set_min_objective(&Objective::call, &obj);
  double f = 0.0;
  std::string reason;
  try {
    reason = stop_reason(opt.optimize(u, f));
  } catch (const nlopt::roundoff_limited&) {
    reason = "round-off limited";
  } catch (const nlopt::forced_stop&) {
    reason = "forced stop";
  } catch (const std::runtime_error& e) {
    reason = std::string("NLopt: ") + e.what();
  }
  if (!obj.best_u().empty()) u = obj.best_u();
  return reason;
}

struct StartPlan {
  std::vector<double> u0;
  bool global = true;
};

}  // namespace

double weighted_mse(std::span<const double> y, std::span<const double> f,
                    std::span<const double> w) noexcept {
  double sum = 0.0, n = 0.0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double e = y[i] - f[i];
    sum += w[i] * e * e;
    n += w[i];
  }
  return n > 0.0 ? sum / n : std::numeric_limits<double>::infinity();
}

FitResult identify(const FrictionModel& initial, const FitData& data, const FitOptions& o) {
  const auto t_start = Clock::now();
  // Time parameters (unit "s", e.g. a step time) are searched within the
  // recording, not over their catalog bounds, unless the caller narrows them.
  std::vector<BoundsOverride> bounds;
  for (const auto& p : initial.parameters()) {
    if (p.unit == "s" && !p.fixed && !data.motion.empty())
      bounds.push_back({p.name, data.motion.front().t, data.motion.back().t});
  }
  bounds.insert(bounds.end(), o.bounds.begin(), o.bounds.end());
  const ParameterMap map(initial.parameters(), bounds);
  if (map.size() == 0) throw std::invalid_argument("identify: the model has no free parameters");
  const std::size_t n = map.size();

  const Scored full = full_rate(data);
  const Scored coarse = decimated(data, o.global_sample_period_s);

  // Start points: deterministic from the seed and the start's index only.
  std::vector<StartPlan> plans;
  const int starts = std::max(1, o.starts);
  const auto u_init = map.to_unit(map.template_values());
  for (int s = 0; s < starts; ++s) {
    std::mt19937_64 rng(o.seed * 1000003ULL + static_cast<std::uint64_t>(s));
    StartPlan p{u_init, o.global_stage};
    if (s > 0 && !o.extra_starts.empty() && static_cast<std::size_t>(s) <= o.extra_starts.size()) {
      p.u0 = map.to_unit(o.extra_starts[static_cast<std::size_t>(s - 1)]);
    } else if (s > 0 && o.global_stage) {
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      for (auto& v : p.u0)
        v = uni(rng);
    } else if (s > 0) {
      std::normal_distribution<double> gauss(0.0, o.warm_perturbation);
      for (auto& v : p.u0)
        v = std::clamp(v + gauss(rng), 0.0, 1.0);
    }
    plans.push_back(std::move(p));
  }

  SharedProgress shared;
  std::vector<StartOutcome> outcomes(plans.size());
  std::vector<std::vector<double>> best_u(plans.size());
  std::vector<std::exception_ptr> errors(plans.size());
  std::atomic<int> next{0};
  const nlopt::algorithm local_alg = nlopt::LN_BOBYQA;

  const auto run_start = [&](int s) {
    const auto t0 = Clock::now();
    // NLopt's random stream is thread-local: seeding it here, per start,
    // makes the start reproducible whichever thread runs it.
    nlopt::srand(static_cast<unsigned long>(o.seed * 7919ULL + static_cast<std::uint64_t>(s)));
    Objective obj(initial, map, shared);
    obj.set_full_size(full.motion.size());
    std::vector<double> u = plans[static_cast<std::size_t>(s)].u0;
    StartOutcome& out = outcomes[static_cast<std::size_t>(s)];
    out.index = s;
    const std::vector<double> lower(n, 0.0), upper(n, 1.0);
    if (plans[static_cast<std::size_t>(s)].global) {
      nlopt::opt g(o.global_algorithm.c_str(), static_cast<unsigned>(n));
      g.set_lower_bounds(lower);
      g.set_upper_bounds(upper);
      g.set_maxeval(o.global_evaluations);
      if (o.global_population > 0) g.set_population(static_cast<unsigned>(o.global_population));
      if (o.global_algorithm.find("MLSL") != std::string::npos) {
        // MLSL runs local searches from low-discrepancy points; each local
        // search is a short, loose BOBYQA.
        nlopt::opt inner(local_alg, static_cast<unsigned>(n));
        inner.set_xtol_rel(1e-3);
        inner.set_ftol_rel(1e-4);
        inner.set_maxeval(o.mlsl_local_evaluations);
        inner.set_initial_step(0.05);
        g.set_local_optimizer(inner);
      }
      obj.use(coarse);
      run_nlopt(g, obj, u);
      out.global_rmse = std::sqrt(obj.best());
    }
    shared.in_local.fetch_add(1);
    const auto polish = [&](const Scored& scored, int evaluations, double step) {
      nlopt::opt l(local_alg, static_cast<unsigned>(n));
      l.set_lower_bounds(lower);
      l.set_upper_bounds(upper);
      l.set_maxeval(evaluations);
      l.set_xtol_rel(1e-6);
      l.set_ftol_rel(1e-9);
      l.set_initial_step(step);
      obj.use(scored);
      return run_nlopt(l, obj, u);
    };
    // First on the cheap decimated data (most of the descent), then a short
    // polish on the full-rate data, which is what the result is judged on.
    if (o.coarse_local_evaluations > 0 && coarse.motion.size() < full.motion.size())
      polish(coarse, o.coarse_local_evaluations, 0.05);
    out.stop_reason = polish(full, o.local_evaluations, 0.01);
    out.rmse = std::sqrt(obj.best());
    out.evaluations = obj.evaluations();
    out.seconds = seconds_since(t0);
    best_u[static_cast<std::size_t>(s)] = u;
  };

  const int hw = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  const int workers = std::min(starts, o.threads > 0 ? o.threads : hw);
  std::vector<std::thread> pool;
  for (int w = 0; w < workers; ++w) {
    pool.emplace_back([&] {
      for (int s = next.fetch_add(1); s < starts; s = next.fetch_add(1)) {
        try {
          run_start(s);
        } catch (...) {
          errors[static_cast<std::size_t>(s)] = std::current_exception();
        }
        shared.starts_done.fetch_add(1);
      }
    });
  }
  const auto report = [&](const char* stage) {
    if (!o.progress) return;
    FitProgress p;
    p.stage = stage;
    p.starts_done = shared.starts_done.load();
    p.starts_total = starts;
    p.evaluations = shared.evaluations.load();
    const double best = shared.best_mse.load();
    p.best_rmse = std::isfinite(best) ? std::sqrt(best) : std::nan("");
    p.elapsed_s = seconds_since(t_start);
    o.progress(p);
  };
  while (shared.starts_done.load() < starts) {
    std::this_thread::sleep_for(std::chrono::duration<double>(o.progress_interval_s));
    report(shared.in_local.load() > 0 ? "local" : "global");
  }
  for (auto& t : pool)
    t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }

  // Best start; ties go to the lower index, so the choice is deterministic.
  int best = 0;
  for (int s = 1; s < starts; ++s) {
    if (outcomes[static_cast<std::size_t>(s)].rmse < outcomes[static_cast<std::size_t>(best)].rmse)
      best = s;
  }
  FitResult r;
  map.to_values(best_u[static_cast<std::size_t>(best)], r.values);
  r.model = initial.clone();
  r.model->set_values(r.values);
  r.simulated = simulate_friction(*r.model, data.motion);
  r.train_rmse = std::sqrt(weighted_mse(data.measured, r.simulated, full.weight));
  // A search with a small budget can end worse on the full-rate data than it
  // began (its descent ran on the decimated data): never return worse than
  // the starting values.
  {
    auto start_model = initial.clone();
    auto start_sim = simulate_friction(*start_model, data.motion);
    const double start_rmse = std::sqrt(weighted_mse(data.measured, start_sim, full.weight));
    if (start_rmse < r.train_rmse) {
      r.values.clear();
      for (const auto& p : initial.parameters())
        r.values.push_back(p.value);
      r.model = std::move(start_model);
      r.simulated = std::move(start_sim);
      r.train_rmse = start_rmse;
    }
  }
  r.starts = std::move(outcomes);
  r.best_start = best;
  for (const auto& s : r.starts)
    r.evaluations += s.evaluations;
  r.global_algorithm = o.global_stage ? o.global_algorithm : "";
  r.local_algorithm = nlopt::algorithm_name(local_alg);
  r.seconds = seconds_since(t_start);
  report("done");
  return r;
}

std::string adapt_scale_to_data(FrictionModel& model, const FitData& data) {
  auto* tsm = dynamic_cast<TsmFrictionModel*>(&model);
  if (tsm == nullptr || data.measured.empty()) return "";
  // The data's sliding friction: a high quantile of |F| on scored samples.
  std::vector<double> mag;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (data.role[i] != SampleRole::ignored) mag.push_back(std::fabs(data.measured[i]));
  }
  if (mag.empty()) return "";
  const auto k = static_cast<std::ptrdiff_t>(0.9 * static_cast<double>(mag.size() - 1));
  std::nth_element(mag.begin(), mag.begin() + k, mag.end());
  const double scale = mag[static_cast<std::size_t>(k)];
  const double level = scale / tsm->spec().gamma;  // the level the fit would need
  if (!(scale > 0.0) || (level >= 0.1 && level <= 5.0)) return "";
  // gamma c with theta and the levels unchanged scales the start model's
  // friction by c (z is unchanged): the start now has the data's scale, and
  // the levels the fit needs are O(1), well inside their bounds.
  const double c = level;
  TsmModelSpec s = tsm->spec();
  s.gamma *= c;
  std::vector<double> values;
  for (const auto& p : TsmFrictionModel(s).parameters())
    values.push_back(p.value);
  model.set_values(values);
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "core.gamma set to %.4g for the data's friction scale (%.3g N) so the levels "
                "stay inside their bounds; gamma is not identifiable, it only scales the levels",
                s.gamma, scale);
  return buf;
}

}  // namespace tsmh::estimator
