#include "master_devices/types.hpp"

namespace tsmh::master_devices {

std::string_view to_string(DeviceStatus s) {
  switch (s) {
    case DeviceStatus::kClosed:
      return "CLOSED";
    case DeviceStatus::kOk:
      return "OK";
    case DeviceStatus::kDisconnected:
      return "DISCONNECTED";
    case DeviceStatus::kFault:
      return "FAULT";
  }
  return "?";
}

std::string_view to_string(FaultCode f) {
  switch (f) {
    case FaultCode::kNone:
      return "none";
    case FaultCode::kDeviceReported:
      return "device reported";
    case FaultCode::kWorkspace:
      return "workspace exceeded";
    case FaultCode::kBadReports:
      return "malformed reports";
    case FaultCode::kHostRequested:
      return "host requested";
    case FaultCode::kHandshake:
      return "handshake";
    case FaultCode::kLinkLost:
      return "link lost";
    case FaultCode::kOtherSession:
      return "another master session on the link";
  }
  return "?";
}

}  // namespace tsmh::master_devices
