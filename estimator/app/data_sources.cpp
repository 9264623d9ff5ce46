#include "data_sources.hpp"

#include <iostream>

#include "files/input_file.hpp"

namespace tsmh::tsm_cli {

estimator::Recording DataSources::load(const std::filesystem::path& path,
                                       std::optional<double> radius,
                                       const estimator::RecordingRequirements& need) const {
  if (!std::filesystem::exists(path))
    throw estimator::DataError(path.string(), 0, "", "no such file");
  estimator::Recording rec;
  bool read = false;
  // Before any source looks at its first bytes: a FIFO or a device is
  // refused at once (opening a FIFO to sniff it blocked), and so is a
  // recording over the size bound.
  try {
    files::InputFile probe(path, files::kMaxRecordingBytes);
  } catch (const files::FileError& e) {
    throw estimator::DataError(path.string(), 0, "", e.why());
  }
  for (const auto& s : sources_) {
    if (s.accepts(path)) {
      rec = s.load(path, radius, need);
      read = true;
      break;
    }
  }
  if (!read) rec = estimator::read_recording_csv(path, radius, need);
  // Said once, here, for every command that reads DATA.
  for (const auto& w : rec.warnings)
    std::cerr << "tsm: warning: " << path.string() << ": " << w << "\n";
  for (const auto& note : rec.notes)
    std::cerr << "tsm: note: " << note << "\n";
  return rec;
}

}  // namespace tsmh::tsm_cli
