// Includes one public header of every exported library (tests the installed
// include folders and the link interface).
#include <tsmh/master_state_t.hpp>

#include "bridge/lcm_url.hpp"
#include "config/field_reader.hpp"
#include "haptics/server_config.hpp"
#include "master_devices/lcm_device.hpp"
#include "master_devices/protocol.hpp"
#include "realtime/clock.hpp"
#include "realtime/histogram.hpp"
#include "realtime/latest_value.hpp"

int main() {
  tsmh::realtime::LatestValue<int> cell;
  cell.store(tsmh::realtime::monotonic_now_ns() > 0 ? 1 : 0);
  int v = 0;
  return cell.load(v) == 1 && v == 1 ? 0 : 1;
}
