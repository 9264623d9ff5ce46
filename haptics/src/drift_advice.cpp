#include "haptics/drift_advice.hpp"

#include <cstdio>

#include "realtime/joint_names.hpp"

namespace tsmh::haptics {

std::string drift_advice(int joint, double scale, const DriftAdviceContext& ctx) {
  char head[200];
  std::snprintf(head, sizeof head,
                "friction drift suspected on %s: in free motion the measured proximal torque "
                "fits %.2fx the friction the model predicts",
                realtime::joint_name(static_cast<std::size_t>(joint)).c_str(), scale);
  std::string s = head;
  if (scale < 1.0) {
    s += ". Less friction than identified: ";
    if (ctx.paper_preset)
      s += "this joint uses the `paper` preset, fitted on the paper's robot; a robot (or a stub "
           "such as slave-node-skeleton's) with less sheath friction reads as drift. ";
    s += "Likely causes: parameters identified on another robot or routing, sheaths "
         "straightened since, or a load-cell gain too low";
  } else {
    s += ". More friction than identified: likely causes: the sheaths re-routed or bent more "
         "tightly than when identified, a tendon pretension raised, or a load-cell gain too high";
  }
  s += ". To do: move the instrument in free space (strokes of 0.3 rad or more each way) and ";
  if (ctx.master_has_calibrate_button) s += "press the master's recalibrate button, or ";
  s += "run `haptic-server --config " +
       (ctx.config_path.empty() ? std::string("FILE") : ctx.config_path) +
       " --request-recalibration`";
  s += "; for a lasting fix, fit the joint's parameters (`tsm fit`, docs/real-robot.md, "
       "\"Calibration without a tip sensor\")";
  return s;
}

}  // namespace tsmh::haptics
