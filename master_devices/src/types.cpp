#include "master_devices/types.hpp"

#include "realtime/enum_names.hpp"

namespace tsmh::master_devices {

std::string_view to_string(DeviceStatus s) {
  return realtime::enum_name<DeviceStatus::kFault>(s, {"CLOSED", "OK", "DISCONNECTED", "FAULT"});
}

std::string_view to_string(FaultCode f) {
  return realtime::enum_name<FaultCode::kOtherSession>(
      f, {"none", "device reported", "workspace exceeded", "malformed reports", "host requested",
          "handshake", "link lost", "another master session on the link"});
}

}  // namespace tsmh::master_devices
