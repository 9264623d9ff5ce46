#include "estimator/identification.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <mutex>
#include <nlopt.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>
#include <utility>

#include "estimator/fit_metrics.hpp"
#include "estimator/parameter_map.hpp"
#include "estimator/separable_fit.hpp"
#include "estimator/simulate.hpp"
#include "estimator/tsm_model.hpp"
#include "realtime/quantile.hpp"

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
  return {d.motion, d.measured, d.weights(SampleRole::kTrain)};
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
    s.weight.push_back(d.role[i] == SampleRole::kTrain ? 1.0 : 0.0);
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

// NLopt's endings that leave a result, in words (its codes are not 0..N, so
// a table of pairs rather than realtime::enum_name).
std::string stop_reason(nlopt::result r) {
  static constexpr std::pair<nlopt::result, const char*> kReasons[] = {
      {nlopt::SUCCESS, "success"},
      {nlopt::STOPVAL_REACHED, "target cost reached"},
      {nlopt::FTOL_REACHED, "cost converged"},
      {nlopt::XTOL_REACHED, "parameters converged"},
      {nlopt::MAXEVAL_REACHED, "evaluation budget used"},
      {nlopt::MAXTIME_REACHED, "time budget used"},
      {nlopt::ROUNDOFF_LIMITED, "round-off limited"}};
  for (const auto& [code, words] : kReasons)
    if (code == r) return words;
  return "stopped (" + std::to_string(static_cast<int>(r)) + ")";
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

namespace {

// ---------------------------------------------------------------------------
// method "lm": informed multi-start + Levenberg-Marquardt.
//
// The model is smooth in its parameters for a fixed motion (the switches in
// eqs. 4-11 depend on the motion, not on the parameters), so a Gauss-Newton
// method with a finite-difference Jacobian converges in a few dozen model
// runs per parameter where derivative-free searches need thousands; the
// local optima that trapped those searches (lambda, kappa1 at their bounds)
// are avoided by starting from what the data itself says about the levels
// and the stiffness, over a small grid of the strongly nonlinear shapes.

// Residuals r = [e_i / sqrt(N) on scored samples; sqrt(alpha) (u - u_ref)]:
// |r|^2 = mean squared error + alpha |u - u_ref|^2.
class LmProblem {
 public:
  LmProblem(const FrictionModel& proto, const ParameterMap& map, const Scored& data, double alpha,
            int threads, SharedProgress& shared, bool full_rate)
      : map_(map), data_(data), alpha_(alpha), shared_(shared), full_rate_(full_rate) {
    for (std::size_t i = 0; i < data.weight.size(); ++i) {
      if (data.weight[i] > 0.0) idx_.push_back(i);
    }
    scale_ = idx_.empty() ? 0.0 : 1.0 / std::sqrt(static_cast<double>(idx_.size()));
    for (int k = 0; k < std::max(1, threads); ++k) {
      models_.push_back(proto.clone());
      buffers_.emplace_back(data.motion.size());
      values_.emplace_back();
    }
  }

  std::size_t rows() const { return idx_.size() + map_.size(); }
  void set_reference(std::vector<double> u) { u_ref_ = std::move(u); }
  long evaluations() const { return evaluations_.load(); }

  // Residual vector at u with worker k's model; returns |r|^2 (1e30 when the
  // model refuses the values or diverges).
  double residuals(const std::vector<double>& u, Eigen::VectorXd& r, std::size_t k = 0) {
    ++evaluations_;
    shared_.evaluations.fetch_add(1, std::memory_order_relaxed);
    r.resize(static_cast<Eigen::Index>(rows()));
    map_.to_values(u, values_[k]);
    try {
      models_[k]->set_values(values_[k]);
    } catch (const std::invalid_argument&) {
      r.setConstant(1e15);
      return 1e30;
    }
    simulate_friction_into(*models_[k], data_.motion, buffers_[k]);
    const auto& f = buffers_[k];
    double mse = 0.0;
    for (std::size_t j = 0; j < idx_.size(); ++j) {
      const double e = (data_.measured[idx_[j]] - f[idx_[j]]) * scale_;
      r(static_cast<Eigen::Index>(j)) = e;
      mse += e * e;
    }
    const double sa = std::sqrt(alpha_);
    double cost = mse;
    for (std::size_t j = 0; j < map_.size(); ++j) {
      const double p = sa * (u[j] - (u_ref_.empty() ? u[j] : u_ref_[j]));
      r(static_cast<Eigen::Index>(idx_.size() + j)) = p;
      cost += p * p;
    }
    if (!std::isfinite(cost)) return 1e30;
    if (full_rate_) shared_.offer(mse);
    return cost;
  }

  // Forward-difference Jacobian of r at u (r0 = r(u)), columns spread over
  // the workers; each column is computed the same way whatever the thread,
  // so the result does not depend on the thread count.
  void jacobian(const std::vector<double>& u, const Eigen::VectorXd& r0, Eigen::MatrixXd& jac) {
    const std::size_t n = map_.size();
    jac.resize(static_cast<Eigen::Index>(rows()), static_cast<Eigen::Index>(n));
    const auto column = [&](std::size_t c, std::size_t k) {
      std::vector<double> up = u;
      double h = kStep;
      if (up[c] + h > 1.0) h = -h;
      up[c] += h;
      Eigen::VectorXd r;
      residuals(up, r, k);
      jac.col(static_cast<Eigen::Index>(c)) = (r - r0) / h;
    };
    const std::size_t workers = std::min(models_.size(), n);
    if (workers <= 1) {
      for (std::size_t c = 0; c < n; ++c)
        column(c, 0);
      return;
    }
    std::vector<std::thread> pool;
    for (std::size_t k = 0; k < workers; ++k) {
      pool.emplace_back([&, k] {
        for (std::size_t c = k; c < n; c += workers)
          column(c, k);
      });
    }
    for (auto& t : pool)
      t.join();
  }

  static constexpr double kStep = 1e-5;  // in normalised units

 private:
  const ParameterMap& map_;
  const Scored& data_;
  double alpha_;
  SharedProgress& shared_;
  bool full_rate_;
  std::vector<std::size_t> idx_;
  double scale_ = 0.0;
  std::vector<double> u_ref_;
  std::vector<std::unique_ptr<FrictionModel>> models_;
  std::vector<std::vector<double>> buffers_, values_;
  std::atomic<long> evaluations_{0};
};

struct LmOutcome {
  std::vector<double> u;
  double cost = 0.0;
  int iterations = 0;
  std::string stop;
};

// Levenberg-Marquardt within the unit box: Marquardt's diagonal scaling, a
// parameter at a bound whose gradient points outwards is held for the step
// (an active set), trial points are clipped to the box.
LmOutcome levenberg_marquardt(LmProblem& p, std::vector<double> u, int max_iterations) {
  const std::size_t n = u.size();
  Eigen::VectorXd r, r_try;
  Eigen::MatrixXd jac;
  LmOutcome out;
  double cost = p.residuals(u, r);
  double mu = 1e-3;
  out.stop = "iteration budget used";
  int small_steps = 0;
  for (int it = 0; it < max_iterations; ++it) {
    out.iterations = it + 1;
    p.jacobian(u, r, jac);
    const Eigen::MatrixXd a = jac.transpose() * jac;
    const Eigen::VectorXd g = jac.transpose() * r;
    std::vector<Eigen::Index> active;
    for (std::size_t j = 0; j < n; ++j) {
      const auto jj = static_cast<Eigen::Index>(j);
      const bool held = (u[j] <= 0.0 && g(jj) > 0.0) || (u[j] >= 1.0 && g(jj) < 0.0);
      if (!held) active.push_back(jj);
    }
    if (active.empty()) {
      out.stop = "every parameter held at a bound";
      break;
    }
    const auto m = static_cast<Eigen::Index>(active.size());
    Eigen::MatrixXd as(m, m);
    Eigen::VectorXd gs(m);
    double dmax = 0.0;
    for (Eigen::Index i = 0; i < m; ++i) {
      gs(i) = g(active[static_cast<std::size_t>(i)]);
      for (Eigen::Index j = 0; j < m; ++j)
        as(i, j) = a(active[static_cast<std::size_t>(i)], active[static_cast<std::size_t>(j)]);
      dmax = std::max(dmax, as(i, i));
    }
    bool accepted = false;
    double cost_new = cost;
    std::vector<double> u_new;
    for (int inner = 0; inner < 12; ++inner) {
      Eigen::MatrixXd lhs = as;
      for (Eigen::Index i = 0; i < m; ++i)
        lhs(i, i) += mu * std::max(as(i, i), 1e-12 * dmax) + 1e-15;
      const Eigen::VectorXd step = lhs.ldlt().solve(-gs);
      u_new = u;
      for (Eigen::Index i = 0; i < m; ++i) {
        const auto j = static_cast<std::size_t>(active[static_cast<std::size_t>(i)]);
        u_new[j] = std::clamp(u[j] + (std::isfinite(step(i)) ? step(i) : 0.0), 0.0, 1.0);
      }
      cost_new = p.residuals(u_new, r_try);
      if (cost_new < cost) {
        accepted = true;
        mu = std::max(mu / 3.0, 1e-9);
        break;
      }
      mu *= 4.0;
      if (mu > 1e8) break;
    }
    if (!accepted) {
      out.stop = "converged (no step reduces the cost)";
      break;
    }
    const double decrease = (cost - cost_new) / cost;
    u = u_new;
    r = r_try;
    cost = cost_new;
    small_steps = decrease < 1e-6 ? small_steps + 1 : 0;
    if (small_steps >= 2) {
      out.stop = "converged (cost change < 1e-6)";
      break;
    }
  }
  out.u = std::move(u);
  out.cost = cost;
  return out;
}

// What the data says about the tendon-sheath model's scale: the sliding
// plateaus (median friction at high speed, each direction) give the levels,
// the slope of F against x where F crosses zero after a reversal gives
// gamma theta. Returns starting value vectors (parameters() order) over a
// small grid of the shapes the data cannot give directly (theta's share of
// the reversal slope against lambda's, the Stribeck decay).
// What the data shows directly: the sliding plateaus (median |F| / gamma
// where |xd| is above half its 95th percentile), in each direction.
struct Plateaus {
  double level_pos = 0.0, level_neg = 0.0;  // sliding levels (F / gamma)
  double v_fast = 0.0;                      // rad/s, the speed above which they are read
  double v_mid = 0.0;                       // rad/s, median speed above v_fast
};

std::optional<Plateaus> sliding_plateaus(const FitData& d, double gamma) {
  std::vector<double> speed;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.role[i] != SampleRole::kIgnored) speed.push_back(std::fabs(d.motion[i].xd));
  }
  Plateaus p;
  p.v_fast = 0.5 * realtime::quantile(speed, 0.95);
  std::vector<double> fpos, fneg, vfast;
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (d.role[i] == SampleRole::kIgnored) continue;
    if (d.motion[i].xd > p.v_fast) fpos.push_back(d.measured[i]);
    if (d.motion[i].xd < -p.v_fast) fneg.push_back(-d.measured[i]);
    if (std::fabs(d.motion[i].xd) > p.v_fast) vfast.push_back(std::fabs(d.motion[i].xd));
  }
  if (fpos.size() < 20 || fneg.size() < 20) return std::nullopt;
  p.level_pos = std::max(0.02, realtime::quantile(fpos, 0.5) / gamma);
  p.level_neg = std::max(0.02, realtime::quantile(fneg, 0.5) / gamma);
  p.v_mid = realtime::quantile(vfast, 0.5);
  return p;
}

// Reversal slopes: after each velocity reversal, regress F on x over the
// samples where |F| is below `f_band` (the steep part); their median, N/rad.
std::optional<double> reversal_slope(const FitData& d, double f_band) {
  std::vector<double> slopes;
  int state = 0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int cnt = 0;
  const auto flush = [&] {
    if (cnt >= 5) {
      const double den = cnt * sxx - sx * sx;
      if (den > 0.0) slopes.push_back(std::fabs((cnt * sxy - sx * sy) / den));
    }
    sx = sy = sxx = sxy = 0.0;
    cnt = 0;
  };
  for (std::size_t i = 0; i < d.size(); ++i) {
    const auto& m = d.motion[i];
    const int now = m.xd > 0.05 ? 1 : (m.xd < -0.05 ? -1 : 0);
    if (now != 0 && now != state) {
      flush();
      state = now;
    }
    if (d.role[i] != SampleRole::kIgnored && std::fabs(d.measured[i]) < f_band && state != 0) {
      sx += m.x;
      sy += d.measured[i];
      sxx += m.x * m.x;
      sxy += m.x * d.measured[i];
      ++cnt;
    }
  }
  flush();
  if (slopes.empty()) return std::nullopt;
  return realtime::quantile(slopes, 0.5);
}

// One start of the grid: the spec with the read levels and slope, the grid's
// theta factor, lambda and Stribeck rate; nullopt when it is not a valid spec.
std::optional<std::vector<double>> grid_start(TsmModelSpec s, const Plateaus& pl, double theta,
                                              double lam, double k1) {
  const bool has_stribeck = s.has(TermKind::kStribeck);
  s.theta = theta;
  const double mu1 = has_stribeck ? 0.5 * std::min(pl.level_pos, pl.level_neg) : 0.0;
  const double strib = mu1 * std::exp(-k1 * pl.v_mid);
  for (auto& t : s.terms) {
    switch (t.kind) {
      case TermKind::kCoulomb:
        t.p[0] = std::max(0.02, pl.level_pos - strib);
        break;
      case TermKind::kDirectionAsymmetry:
        t.p[0] = std::max(0.02, pl.level_neg - strib);
        break;
      case TermKind::kStribeck:
        t.p[0] = mu1;
        t.p[1] = k1;
        break;
      case TermKind::kReversalOffset:
        t.p[0] = lam;
        break;
      case TermKind::kAccelerationDependence:
        // An amplitude and its rate both at 0 (a "flat" start) is a
        // saddle: mu2 (1 - e^(-kappa2 |xdd|)) has no gradient in either.
        // Start such pairs at small values of the paper's order.
        if (!(t.p[0] > 0.0) || !(t.p[1] > 0.0)) {
          t.p[0] = 0.05 * pl.level_pos;
          t.p[1] = 0.03;
        }
        if (!(t.p[2] > 0.0) || !(t.p[3] > 0.0)) {
          t.p[2] = 0.1 * pl.level_neg;
          t.p[3] = 10.0;
        }
        if (!(t.p[4] > 0.1)) t.p[4] = 6.0;
        break;
      default:
        break;
    }
  }
  if (!s.has(TermKind::kDirectionAsymmetry)) {
    for (auto& t : s.terms)
      if (t.kind == TermKind::kCoulomb)
        t.p[0] = std::max(0.02, 0.5 * (pl.level_pos + pl.level_neg) - strib);
  }
  try {
    validate(s);
  } catch (const std::invalid_argument&) {
    return std::nullopt;
  }
  std::vector<double> v;
  for (const auto& p : TsmFrictionModel(s).parameters())
    v.push_back(p.value);
  return v;
}

std::vector<std::vector<double>> informed_starts(const TsmFrictionModel& initial, const FitData& d,
                                                 std::vector<std::string>& notes) {
  const TsmModelSpec& spec = initial.spec();
  const double gamma = spec.gamma;
  const auto pl = sliding_plateaus(d, gamma);
  if (!pl) return {};
  const auto slope = reversal_slope(d, 0.4 * gamma * 0.5 * (pl->level_pos + pl->level_neg));
  if (!slope) return {};
  const double theta_slope = std::clamp(*slope / gamma, 0.2, 500.0);
  char buf[240];
  std::snprintf(buf, sizeof buf,
                "informed starts: sliding plateaus %.3g N (xd > 0) and %.3g N (xd < 0) above "
                "%.3g rad/s, reversal slope %.3g N/rad (theta about %.3g with gamma %.4g)",
                gamma * pl->level_pos, gamma * pl->level_neg, pl->v_fast, theta_slope * gamma,
                theta_slope, gamma);
  notes.push_back(buf);

  std::vector<std::vector<double>> out;
  const double theta_factors[] = {0.35, 1.0};
  const double lambdas[] = {0.05, 0.2, 0.6};
  const double kappas[] = {3.0, 12.0};
  const bool has_stribeck = spec.has(TermKind::kStribeck);
  const bool has_lambda = spec.has(TermKind::kReversalOffset);
  for (double tf : theta_factors) {
    for (double lam : lambdas) {
      if (!has_lambda && lam != lambdas[0]) continue;
      for (double k1 : kappas) {
        if (!has_stribeck && k1 != kappas[0]) continue;
        if (auto v = grid_start(spec, *pl, theta_slope * tf, lam, k1)) out.push_back(std::move(*v));
      }
    }
  }
  return out;
}

// The free parameters both optimisers search. Time parameters (unit "s",
// e.g. a step time) are searched within the recording, not over their
// catalog bounds, unless the caller narrows them.
ParameterMap search_map(const FrictionModel& initial, const FitData& data, const FitOptions& o) {
  std::vector<BoundsOverride> bounds;
  for (const auto& p : initial.parameters()) {
    if (p.unit == "s" && !p.fixed && !data.motion.empty())
      bounds.push_back({p.name, data.motion.front().t, data.motion.back().t});
  }
  bounds.insert(bounds.end(), o.bounds.begin(), o.bounds.end());
  ParameterMap map(initial.parameters(), bounds);
  if (map.size() == 0) throw std::invalid_argument("identify: the model has no free parameters");
  return map;
}

// What both optimisers search and score: the free parameters, the
// full-rate data the result is judged on, and the decimated data of the
// global stage.
struct Search {
  ParameterMap map;
  Scored full;
  Scored coarse;
};

Search make_search(const FrictionModel& initial, const FitData& data, const FitOptions& o) {
  return {search_map(initial, data, o), full_rate(data), decimated(data, o.global_sample_period_s)};
}

int worker_threads(const FitOptions& o) {
  const int hw = static_cast<int>(std::max(1U, std::thread::hardware_concurrency()));
  return std::max(1, o.threads > 0 ? o.threads : hw);
}

// Runs job(0) .. job(total - 1) on up to `threads` workers; while they run,
// calls on_wait() every progress interval (the caller's progress report).
// Returns as soon as the last job ends, not at the next report: a stage that
// ends just after a report would otherwise idle up to a whole interval.
// The first exception a job threw is rethrown once all have finished.
void run_on_workers(int total, int threads, SharedProgress& shared, double interval_s,
                    const std::function<void(int)>& job, const std::function<void()>& on_wait) {
  std::vector<std::exception_ptr> errors(static_cast<std::size_t>(total));
  std::atomic<int> next{0};
  std::mutex m;
  std::condition_variable ended;
  int done = 0;  // guarded by m
  std::vector<std::thread> pool;
  for (int w = 0; w < std::min(threads, total); ++w) {
    pool.emplace_back([&] {
      for (int s = next.fetch_add(1); s < total; s = next.fetch_add(1)) {
        try {
          job(s);
        } catch (...) {
          errors[static_cast<std::size_t>(s)] = std::current_exception();
        }
        shared.starts_done.fetch_add(1);
        const std::lock_guard<std::mutex> lock(m);
        ++done;
        ended.notify_one();
      }
    });
  }
  {
    std::unique_lock<std::mutex> lock(m);
    const auto interval = std::chrono::duration<double>(interval_s);
    while (!ended.wait_for(lock, interval, [&] { return done >= total; })) {
      lock.unlock();
      on_wait();
      lock.lock();
    }
  }
  for (auto& t : pool)
    t.join();
  for (const auto& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

void report_progress(const FitOptions& o, const SharedProgress& shared, const char* stage, int done,
                     int of, Clock::time_point t_start) {
  if (!o.progress) return;
  FitProgress pr;
  pr.stage = stage;
  pr.starts_done = done;
  pr.starts_total = of;
  pr.evaluations = shared.evaluations.load();
  const double best = shared.best_mse.load();
  pr.best_rmse = std::isfinite(best) ? std::sqrt(best) : std::nan("");
  pr.elapsed_s = seconds_since(t_start);
  o.progress(pr);
}

// The result at the best point found (unit coordinates). A search with a
// small budget can end worse on the full-rate data than it began (its
// descent ran on the decimated data): never return worse than the starting
// values.
void set_best_values(FitResult& r, const FrictionModel& initial, const FitData& data,
                     const ParameterMap& map, const std::vector<double>& best_u,
                     const std::vector<double>& weight) {
  map.to_values(best_u, r.values);
  r.model = initial.clone();
  r.model->set_values(r.values);
  r.simulated = simulate_friction(*r.model, data.motion);
  r.train_rmse = std::sqrt(weighted_mse(data.measured, r.simulated, weight));
  auto start_model = initial.clone();
  auto start_sim = simulate_friction(*start_model, data.motion);
  const double start_rmse = std::sqrt(weighted_mse(data.measured, start_sim, weight));
  if (start_rmse < r.train_rmse) {
    r.values.clear();
    for (const auto& p : initial.parameters())
      r.values.push_back(p.value);
    r.model = std::move(start_model);
    r.simulated = std::move(start_sim);
    r.train_rmse = start_rmse;
  }
}

// LM's starting points (full value vectors): the given values, the extra
// ones, then (global) the informed grid, else perturbations of the given
// values.
std::vector<std::vector<double>> lm_starts(const FrictionModel& initial, const FitData& data,
                                           const ParameterMap& map, const FitOptions& o,
                                           std::vector<std::string>& notes) {
  std::vector<std::vector<double>> starts;
  starts.push_back(map.template_values());
  for (const auto& e : o.extra_starts)
    starts.push_back(e);
  if (o.global_stage) {
    const auto* tsm = dynamic_cast<const TsmFrictionModel*>(&initial);
    std::vector<std::vector<double>> informed;
    if (tsm != nullptr) informed = informed_starts(*tsm, data, notes);
    for (auto& v : informed)
      starts.push_back(std::move(v));
    // Models without a known structure (baselines), or data where the
    // plateaus cannot be read: random points, seeded.
    if (informed.empty()) {
      std::mt19937_64 rng(o.seed * 1000003ULL);
      std::uniform_real_distribution<double> uni(0.0, 1.0);
      for (int s = 0; s < std::max(8, 2 * o.starts); ++s) {
        std::vector<double> u(map.size());
        for (auto& v : u)
          v = uni(rng);
        std::vector<double> vals;
        map.to_values(u, vals);
        starts.push_back(std::move(vals));
      }
    }
  } else {
    std::mt19937_64 rng(o.seed * 1000003ULL);
    std::normal_distribution<double> gauss(0.0, o.warm_perturbation);
    const auto u0 = map.to_unit(map.template_values());
    while (static_cast<int>(starts.size()) < o.starts) {
      std::vector<double> u = u0;
      for (auto& v : u)
        v = std::clamp(v + gauss(rng), 0.0, 1.0);
      std::vector<double> vals;
      map.to_values(u, vals);
      starts.push_back(std::move(vals));
    }
  }
  return starts;
}

struct Screened {
  std::vector<double> u;
  double cost = 0.0;
  long evaluations = 0;
};

// The best `count` distinct screened starts (ties to the lower index:
// deterministic).
std::vector<int> choose_distinct(const std::vector<Screened>& screened, int count) {
  std::vector<int> order(screened.size());
  for (std::size_t s = 0; s < screened.size(); ++s)
    order[s] = static_cast<int>(s);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return screened[static_cast<std::size_t>(a)].cost < screened[static_cast<std::size_t>(b)].cost;
  });
  std::vector<int> chosen;
  for (int s : order) {
    if (static_cast<int>(chosen.size()) >= std::max(1, count)) break;
    const auto& u = screened[static_cast<std::size_t>(s)].u;
    const bool distinct = std::all_of(chosen.begin(), chosen.end(), [&](int c) {
      const auto& v = screened[static_cast<std::size_t>(c)].u;
      double d2 = 0.0;
      for (std::size_t j = 0; j < u.size(); ++j)
        d2 += (u[j] - v[j]) * (u[j] - v[j]);
      return std::sqrt(d2) > 0.02;
    });
    if (distinct) chosen.push_back(s);
  }
  return chosen;
}

FitResult identify_lm(const FrictionModel& initial, const FitData& data, const FitOptions& o) {
  const auto t_start = Clock::now();
  const Search search = make_search(initial, data, o);
  const auto& [map, full, coarse] = search;
  const double noise = noise_floor(data.measured);
  const double alpha = o.prior_weight * (std::isfinite(noise) && noise > 0.0 ? noise * noise : 1.0);
  const int threads = worker_threads(o);

  FitResult r;
  const std::vector<std::vector<double>> starts = lm_starts(initial, data, map, o, r.notes);
  SharedProgress shared;
  const int total = static_cast<int>(starts.size());

  // Screening: a short LM from every start on the decimated data, starts
  // spread over the workers (each with its own problem and model clones).
  std::vector<Screened> screened(starts.size());
  const bool screen = coarse.motion.size() < full.motion.size();
  run_on_workers(
      total, threads, shared, o.progress_interval_s,
      [&](int s) {
        const auto u0 = map.to_unit(starts[static_cast<std::size_t>(s)]);
        LmProblem p(initial, map, screen ? coarse : full, alpha, 1, shared, !screen);
        p.set_reference(u0);
        const LmOutcome lo = levenberg_marquardt(p, u0, o.screen_iterations);
        screened[static_cast<std::size_t>(s)] = {lo.u, lo.cost, p.evaluations()};
      },
      [&] { report_progress(o, shared, "screening", shared.starts_done.load(), total, t_start); });
  const std::vector<int> chosen = choose_distinct(screened, o.starts);

  // Polish: LM on the full-rate data. The candidates run side by side on
  // the workers and the threads left over compute Jacobian columns: the
  // candidates are independent and converge in similar numbers of
  // iterations, so this keeps every core busy, where polishing them one
  // after another left the cores idle during each iteration's trial steps.
  // Each candidate's result does not depend on where it ran.
  const int n_chosen = static_cast<int>(chosen.size());
  const int polish_workers = std::max(1, std::min(threads, n_chosen));
  const int column_threads = std::max(1, threads / polish_workers);
  std::vector<std::vector<double>> best_u(chosen.size());
  r.starts.resize(chosen.size());
  shared.starts_done.store(0);
  run_on_workers(
      n_chosen, polish_workers, shared, o.progress_interval_s,
      [&](int c) {
        const auto k = static_cast<std::size_t>(c);
        const auto& sc = screened[static_cast<std::size_t>(chosen[k])];
        LmProblem p(initial, map, full, alpha, column_threads, shared, true);
        p.set_reference(map.to_unit(starts[static_cast<std::size_t>(chosen[k])]));
        const auto t0 = Clock::now();
        const LmOutcome lo = levenberg_marquardt(p, sc.u, o.polish_iterations);
        StartOutcome& out = r.starts[k];
        out.index = chosen[k];
        out.global_rmse = std::sqrt(sc.cost);
        std::vector<double> vals;
        map.to_values(lo.u, vals);
        auto m = initial.clone();
        m->set_values(vals);
        const auto f = simulate_friction(*m, data.motion);
        out.rmse = std::sqrt(weighted_mse(data.measured, f, full.weight));
        out.evaluations = p.evaluations();
        out.seconds = seconds_since(t0);
        out.stop_reason = lo.stop + " after " + std::to_string(lo.iterations) + " iterations";
        best_u[k] = lo.u;
      },
      [&] { report_progress(o, shared, "polish", shared.starts_done.load(), n_chosen, t_start); });
  long evaluations = 0;
  for (const auto& sc : screened)
    evaluations += sc.evaluations;
  for (const auto& out : r.starts)
    evaluations += out.evaluations;
  int best = 0;
  for (std::size_t s = 1; s < r.starts.size(); ++s) {
    if (r.starts[s].rmse < r.starts[static_cast<std::size_t>(best)].rmse)
      best = static_cast<int>(s);
  }
  set_best_values(r, initial, data, map, best_u[static_cast<std::size_t>(best)], full.weight);
  r.best_start = best;
  r.evaluations = evaluations;
  r.screened = total;
  r.global_algorithm = o.global_stage ? "informed multi-start screening" : "";
  r.local_algorithm = "Levenberg-Marquardt (finite-difference Jacobian)";
  r.library = "own Levenberg-Marquardt (Eigen)";
  r.seconds = seconds_since(t_start);
  report_progress(o, shared, "done", n_chosen, n_chosen, t_start);
  return r;
}

// NLopt's start points: deterministic from the seed and the start's index only.
std::vector<StartPlan> nlopt_plans(const ParameterMap& map, const FitOptions& o) {
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
  return plans;
}

constexpr nlopt::algorithm kNloptLocal = nlopt::LN_BOBYQA;

// One NLopt start: the global stage on the decimated data (when planned),
// then BOBYQA, first on the decimated data (most of the descent), then a
// short polish on the full-rate data, which is what the result is judged
// on. `u` holds the start point and receives the best point.
StartOutcome run_nlopt_start(int s, const StartPlan& plan, const FrictionModel& initial,
                             const ParameterMap& map, const Scored& full, const Scored& coarse,
                             const FitOptions& o, SharedProgress& shared, std::vector<double>& u) {
  const auto t0 = Clock::now();
  const std::size_t n = map.size();
  // NLopt's random stream is thread-local: seeding it here, per start,
  // makes the start reproducible whichever thread runs it.
  nlopt::srand(static_cast<unsigned long>(o.seed * 7919ULL + static_cast<std::uint64_t>(s)));
  Objective obj(initial, map, shared);
  obj.set_full_size(full.motion.size());
  u = plan.u0;
  StartOutcome out;
  out.index = s;
  const std::vector<double> lower(n, 0.0), upper(n, 1.0);
  if (plan.global) {
    nlopt::opt g(o.global_algorithm.c_str(), static_cast<unsigned>(n));
    g.set_lower_bounds(lower);
    g.set_upper_bounds(upper);
    g.set_maxeval(o.global_evaluations);
    if (o.global_population > 0) g.set_population(static_cast<unsigned>(o.global_population));
    if (o.global_algorithm.find("MLSL") != std::string::npos) {
      // MLSL runs local searches from low-discrepancy points; each local
      // search is a short, loose BOBYQA.
      nlopt::opt inner(kNloptLocal, static_cast<unsigned>(n));
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
    nlopt::opt l(kNloptLocal, static_cast<unsigned>(n));
    l.set_lower_bounds(lower);
    l.set_upper_bounds(upper);
    l.set_maxeval(evaluations);
    l.set_xtol_rel(1e-6);
    l.set_ftol_rel(1e-9);
    l.set_initial_step(step);
    obj.use(scored);
    return run_nlopt(l, obj, u);
  };
  if (o.coarse_local_evaluations > 0 && coarse.motion.size() < full.motion.size())
    polish(coarse, o.coarse_local_evaluations, 0.05);
  out.stop_reason = polish(full, o.local_evaluations, 0.01);
  out.rmse = std::sqrt(obj.best());
  out.evaluations = obj.evaluations();
  out.seconds = seconds_since(t0);
  return out;
}

FitResult identify_nlopt(const FrictionModel& initial, const FitData& data, const FitOptions& o) {
  const auto t_start = Clock::now();
  const Search search = make_search(initial, data, o);
  const auto& [map, full, coarse] = search;
  const std::vector<StartPlan> plans = nlopt_plans(map, o);
  const int starts = static_cast<int>(plans.size());

  SharedProgress shared;
  std::vector<StartOutcome> outcomes(plans.size());
  std::vector<std::vector<double>> best_u(plans.size());
  run_on_workers(
      starts, std::min(starts, worker_threads(o)), shared, o.progress_interval_s,
      [&](int s) {
        const auto k = static_cast<std::size_t>(s);
        outcomes[k] =
            run_nlopt_start(s, plans[k], initial, map, full, coarse, o, shared, best_u[k]);
      },
      [&] {
        report_progress(o, shared, shared.in_local.load() > 0 ? "local" : "global",
                        shared.starts_done.load(), starts, t_start);
      });

  // Best start; ties go to the lower index, so the choice is deterministic.
  int best = 0;
  for (int s = 1; s < starts; ++s) {
    if (outcomes[static_cast<std::size_t>(s)].rmse < outcomes[static_cast<std::size_t>(best)].rmse)
      best = s;
  }
  FitResult r;
  set_best_values(r, initial, data, map, best_u[static_cast<std::size_t>(best)], full.weight);
  r.starts = std::move(outcomes);
  r.best_start = best;
  for (const auto& s : r.starts)
    r.evaluations += s.evaluations;
  r.global_algorithm = o.global_stage ? o.global_algorithm : "";
  r.local_algorithm = nlopt::algorithm_name(kNloptLocal);
  r.library = "NLopt";
  r.seconds = seconds_since(t_start);
  report_progress(o, shared, "done", shared.starts_done.load(), starts, t_start);
  return r;
}
}  // namespace

FitResult identify(const FrictionModel& initial, const FitData& data, const FitOptions& o) {
  // A model with distributed slip is linear in most of its parameters: the
  // separable method solves those exactly (separable_fit.hpp).
  if (o.method == "separable" || (o.method == "lm" && has_linear_block(initial)))
    return identify_separable(initial, data, o);
  if (o.method == "nlopt") return identify_nlopt(initial, data, o);
  if (o.method != "lm")
    throw std::invalid_argument("identify: unknown method '" + o.method +
                                "' (lm, separable or nlopt)");
  return identify_lm(initial, data, o);
}

std::string adapt_scale_to_data(FrictionModel& model, const FitData& data) {
  auto* tsm = dynamic_cast<TsmFrictionModel*>(&model);
  if (tsm == nullptr || data.measured.empty()) return "";
  // The data's sliding friction: a high quantile of |F| on scored samples.
  std::vector<double> mag;
  for (std::size_t i = 0; i < data.size(); ++i) {
    if (data.role[i] != SampleRole::kIgnored) mag.push_back(std::fabs(data.measured[i]));
  }
  if (mag.empty()) return "";
  const double scale = realtime::quantile(std::move(mag), 0.9);
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
