#include "delay_relay/link_impairment.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tsmh::delay_relay {

void validate(const ImpairmentParams& p, const char* where) {
  const std::string w = std::string(where) + ".";
  if (!(p.delay_s >= 0.0) || !std::isfinite(p.delay_s) || p.delay_s > 60.0)
    throw std::invalid_argument(w + "delay: must be within [0, 60] s");
  if (!(p.jitter_s >= 0.0) || !(p.jitter_s <= p.delay_s))
    throw std::invalid_argument(w + "jitter: must be within [0, delay]");
  if (!(p.drop_fraction >= 0.0) || !(p.drop_fraction <= 1.0))
    throw std::invalid_argument(w + "drop: must be a fraction within [0, 1]");
}

LinkImpairment::LinkImpairment(const ImpairmentParams& p, std::uint64_t seed) : p_(p), rng_(seed) {
  validate(p_, "link");
}

std::int64_t LinkImpairment::schedule(std::int64_t arrival_ns) noexcept {
  // Both draws are taken for every message, so the delay of message k does
  // not depend on whether earlier ones were dropped (runs that differ only in
  // drop_fraction see the same jitter sequence).
  const double u_drop = rng_.uniform();
  const double u_jitter = rng_.uniform();
  if (u_drop < p_.drop_fraction) {
    ++dropped_;
    return kDropped;
  }
  const double delay_s = p_.delay_s + p_.jitter_s * (2.0 * u_jitter - 1.0);
  const std::int64_t at = arrival_ns + static_cast<std::int64_t>(std::llround(delay_s * 1e9));
  last_release_ns_ = std::max(last_release_ns_, at);
  ++passed_;
  return last_release_ns_;
}

}  // namespace tsmh::delay_relay
