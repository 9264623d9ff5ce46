#include "data_sources.hpp"

namespace tsmh::tsm_cli {

estimator::Recording DataSources::load(const std::filesystem::path& path,
                                       std::optional<double> radius,
                                       const estimator::RecordingRequirements& need) const {
  if (!std::filesystem::exists(path))
    throw estimator::DataError(path.string(), 0, "", "no such file");
  for (const auto& s : sources_) {
    if (s.accepts(path)) return s.load(path, radius, need);
  }
  return estimator::read_recording_csv(path, radius, need);
}

}  // namespace tsmh::tsm_cli
