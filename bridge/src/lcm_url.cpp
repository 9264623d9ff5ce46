#include "bridge/lcm_url.hpp"

#include <cstdlib>
#include <lcm/lcm-cpp.hpp>

namespace tsmh::bridge {

std::string resolve_lcm_url(std::string_view cli_url, const char* env_value) {
  if (!cli_url.empty()) return lcmtypes::parse_lcm_url(cli_url).text;
  if (env_value != nullptr && env_value[0] != '\0') {
    try {
      return lcmtypes::parse_lcm_url(env_value).text;
    } catch (const LcmUrlError& e) {
      throw LcmUrlError(std::string("$LCM_DEFAULT_URL: ") + e.what());
    }
  }
  return std::string(kDefaultLcmUrl);
}

std::string resolve_lcm_url(std::string_view cli_url) {
  return resolve_lcm_url(cli_url, std::getenv("LCM_DEFAULT_URL"));
}

std::unique_ptr<lcm::LCM> open_lcm(const std::string& url) {
  lcmtypes::parse_lcm_url(url);  // LcmUrlError before LCM reads it its own way
  auto lcm = std::make_unique<lcm::LCM>(url);
  if (lcm->good()) return lcm;
  std::string msg = "cannot open LCM at '" + url + "'";
  if (url.rfind("udpm://", 0) == 0 || url.empty()) {
    msg +=
        ": LCM's multicast self-test failed, most likely because no route covers the multicast "
        "group (no network, or only a default route that does not reach this group). To keep "
        "LCM traffic on this host, as root run:\n"
        "  ip link set lo multicast on; ip route add 224.0.0.0/4 dev lo\n"
        "(details: http://lcm-proj.github.io/multicast_setup.html; choose another network with "
        "--lcm-url or LCM_DEFAULT_URL)";
  } else {
    msg +=
        ": check the provider and options of the URL given with --lcm-url or LCM_DEFAULT_URL "
        "(e.g. udpm://239.255.76.67:7667?ttl=0, memq://, file:///path.lcmlog?mode=w)";
  }
  throw BridgeError(msg);
}

}  // namespace tsmh::bridge
