#ifndef CALIB_TOOLS_REPORT_DEPLOY_ADVICE_H_
#define CALIB_TOOLS_REPORT_DEPLOY_ADVICE_H_

#include <nlohmann/json.hpp>
#include <string>

// What `calib diagnose` tells a user to deploy, from its JSON (either problem): the single
// estimate to put in the robot's configuration (the final fit, with the radii after a radius
// change), the time offset a driver can apply, and the adopted effects that a standard
// diff_drive_controller cannot express.
namespace calib {

struct DeployAdvice {
  nlohmann::ordered_json json;  // The diagnosis JSON's "deploy".
  std::string summary;          // "  deploy: ..." lines.
};

DeployAdvice AdviseDeployment(const nlohmann::ordered_json& diagnosis);

}  // namespace calib

#endif  // CALIB_TOOLS_REPORT_DEPLOY_ADVICE_H_
