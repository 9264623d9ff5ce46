#pragma once
// The text haptic-server logs when the drift monitor fires: what it saw, the
// likely cause for the direction of the mismatch, and what to do with the
// means this setup really has (a recalibrate button only if the master has
// one). Main thread only: it builds a std::string.

#include <string>

namespace tsmh::haptics {

struct DriftAdviceContext {
  /// The server's --config path, for the --request-recalibration command.
  std::string config_path;
  /// The master reports a recalibrate button (DeviceSpec::has_calibrate_button).
  bool master_has_calibrate_button = false;
  /// The joint's friction parameters are the built-in `paper` preset.
  bool paper_preset = false;
};

/// `scale`: the friction scale the free motion asks for (1 = the model fits).
std::string drift_advice(int joint, double scale, const DriftAdviceContext& ctx);

}  // namespace tsmh::haptics
