// Includes one public header of every exported library (tests the installed
// include folders and the link interface).
#include <tsmh/master_state_t.hpp>

#include "bridge/lcm_url.hpp"
#include "haptics/server_config.hpp"
#include "master_devices/lcm_device.hpp"
#include "master_devices/protocol.hpp"

int main() {
  return 0;
}
