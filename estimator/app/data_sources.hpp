#pragma once
// Where `tsm` reads DATA from. The CSV contract is built in; other formats
// (LCM logs, from the bridge module) register themselves here at start-up,
// so the estimator library never depends on them.

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "estimator/recording.hpp"

namespace tsmh::tsm_cli {

struct DataSource {
  std::string name;  ///< e.g. "lcm-log", for messages
  /// True when this source reads the file (by content, e.g. a magic number).
  std::function<bool(const std::filesystem::path&)> accepts;
  std::function<estimator::Recording(const std::filesystem::path&, std::optional<double>,
                                     const estimator::RecordingRequirements&)>
      load;
};

class DataSources {
 public:
  void add(DataSource source) { sources_.push_back(std::move(source)); }
  /// The first registered source that accepts the file, else the CSV reader.
  estimator::Recording load(const std::filesystem::path& path, std::optional<double> radius,
                            const estimator::RecordingRequirements& need) const;

 private:
  std::vector<DataSource> sources_;
};

}  // namespace tsmh::tsm_cli
