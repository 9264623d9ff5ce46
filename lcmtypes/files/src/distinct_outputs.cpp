#include "files/distinct_outputs.hpp"

#include <sys/stat.h>

#include <optional>

#include "files/input_file.hpp"
#include "files/link_target.hpp"

namespace tsmh::files {
namespace {

namespace fs = std::filesystem;

// What a path names on disk: an existing file's (device, inode), or for a
// file still to be created its folder's (device, inode) and its name.
struct Identity {
  dev_t dev = 0;
  ino_t ino = 0;
  std::string name;  ///< empty for an existing file
  mode_t mode = 0;   ///< of the existing file (0: not yet created)
  bool operator==(const Identity& o) const {
    return dev == o.dev && ino == o.ino && name == o.name;
  }
};

std::optional<Identity> identify(const fs::path& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0) return Identity{st.st_dev, st.st_ino, "", st.st_mode};
  const fs::path target = final_link_target(path);
  fs::path folder = target.parent_path();
  if (folder.empty()) folder = ".";
  if (::stat(folder.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) return std::nullopt;
  return Identity{st.st_dev, st.st_ino, target.filename().string(), 0};
}

// The folder an existing file sits in, as named (a link's own folder) and as
// resolved: replacing either entry of that name would lose the file.
std::vector<Identity> folders_of(const fs::path& path) {
  std::vector<Identity> out;
  for (const fs::path& p : {path, final_link_target(path)}) {
    fs::path folder = p.parent_path();
    if (folder.empty()) folder = ".";
    if (auto id = identify(folder)) out.push_back(*id);
  }
  return out;
}

bool written_through(const Identity& id) {
  return id.mode != 0 && !S_ISREG(id.mode) && !S_ISDIR(id.mode);
}

std::string quoted(const NamedOutput& o) {
  return o.role + " " + o.path.string();
}

}  // namespace

void check_distinct_outputs(const std::vector<NamedInput>& inputs,
                            const std::vector<NamedOutput>& outputs) {
  struct Seen {
    const NamedOutput* output;
    Identity id;
  };
  std::vector<Seen> seen;
  for (const NamedOutput& o : outputs) {
    if (o.path.empty()) continue;
    const auto id = identify(o.path);
    if (!id || written_through(*id)) continue;  // a missing folder is reported elsewhere
    for (const NamedInput& in : inputs) {
      if (in.path.empty()) continue;
      const auto in_id = identify(in.path);
      if (!in_id || in_id->name.size() > 0) continue;  // not there: its reader says so
      if (*in_id == *id)
        throw FileError(quoted(o), "is the same file as " + in.role + " " + in.path.string() +
                                       (o.folder ? "" : "; writing it would destroy " + in.role) +
                                       ": choose another name");
      if (o.folder && id->name.empty()) {
        for (const Identity& f : folders_of(in.path)) {
          if (f == *id)
            throw FileError(quoted(o),
                            in.role + " " + in.path.string() +
                                " lies in this folder, whose files the run creates or replaces: "
                                "choose another folder");
        }
      }
    }
    for (const Seen& s : seen) {
      if (s.id == *id)
        throw FileError(quoted(o), "is the same file as " + quoted(*s.output) +
                                       "; one would overwrite the other: choose another name");
    }
    seen.push_back({&o, *id});
  }
}

}  // namespace tsmh::files
