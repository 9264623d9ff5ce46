#pragma once
// Names a word the command line does not know, with the nearest valid one:
// "unknown subcommand 'fitt'; did you mean 'fit'?", "unknown option
// '--outptu'; did you mean --output?". CLI11 alone reports the first rule
// a typo breaks instead ("A subcommand is required", "--output is
// required"), which hides the typo itself; so the words are checked before
// CLI11 parses them.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <iostream>
#include <string>
#include <string_view>
#include <vector>

namespace tsmh::cli_words {

/// Levenshtein distance (insert, delete, substitute; a swap of two
/// neighbours counts 1, the commonest typo).
inline std::size_t edit_distance(std::string_view a, std::string_view b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i)
    d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j)
    d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[n][m];
}

/// The candidate nearest to `word`, if near enough to be a typo of it (at
/// most a third of its letters wrong, at least 2 allowed); else empty.
inline std::string nearest(std::string_view word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::max<std::size_t>(2, word.size() / 3) + 1;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  return best;
}

namespace detail {

// Which names of an option to look in: &CLI::Option::get_lnames (long) or
// &CLI::Option::get_snames (short).
using OptionNames = const std::vector<std::string>& (CLI::Option::*)() const;

// The option of `app` or one of its parents that has `name` among its `names`.
inline const CLI::Option* find_option(const CLI::App& app, const std::string& name,
                                      OptionNames names) {
  for (const CLI::App* a = &app; a != nullptr; a = a->get_parent()) {
    for (const CLI::Option* o : a->get_options({})) {
      const auto& n = (o->*names)();
      if (std::find(n.begin(), n.end(), name) != n.end()) return o;
    }
  }
  return nullptr;
}

inline std::vector<std::string> long_names(const CLI::App& app) {
  std::vector<std::string> out;
  for (const CLI::App* a = &app; a != nullptr; a = a->get_parent()) {
    for (const CLI::Option* o : a->get_options({}))
      for (const auto& l : o->get_lnames())
        out.push_back(l);
  }
  return out;
}

inline bool takes_value(const CLI::Option* o) {
  return o->get_type_size_max() > 0;
}

}  // namespace detail

/// The first word of argv (argv[1..]) that `app` does not know, as an error
/// message naming it and the nearest valid word; empty when every word is
/// known. Positional values pass; option values are skipped.
inline std::string unknown_word(const CLI::App& app, int argc, const char* const* argv) {
  const CLI::App* cur = &app;
  bool sub_chosen = false;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    if (arg.rfind("--", 0) == 0) {
      const auto eq = arg.find('=');
      const std::string name = arg.substr(2, eq == std::string::npos ? std::string::npos : eq - 2);
      const CLI::Option* o = detail::find_option(*cur, name, &CLI::Option::get_lnames);
      if (o == nullptr) {
        const std::string near = nearest(name, detail::long_names(*cur));
        return "unknown option '--" + name + "'" +
               (near.empty() ? "" : "; did you mean --" + near + "?");
      }
      if (detail::takes_value(o) && eq == std::string::npos) ++i;
    } else if (arg.size() >= 2 && arg[0] == '-' && arg[1] != '-' &&
               !(arg[1] >= '0' && arg[1] <= '9') && arg[1] != '.') {
      // Short options: a value either follows (-o FILE) or is attached (-oFILE).
      const CLI::Option* o = detail::find_option(*cur, arg.substr(1, 1), &CLI::Option::get_snames);
      if (o == nullptr) return "unknown option '" + arg.substr(0, 2) + "'";
      if (detail::takes_value(o) && arg.size() == 2) ++i;
    } else if (!sub_chosen) {
      // Named subcommands only (CLI11 keeps option groups among them, unnamed).
      const auto subs =
          cur->get_subcommands([](const CLI::App* a) { return !a->get_name().empty(); });
      if (subs.empty()) continue;  // a positional value
      std::vector<std::string> names;
      const CLI::App* match = nullptr;
      for (const CLI::App* s : subs) {
        names.push_back(s->get_name());
        if (s->check_name(arg)) match = s;
      }
      if (match != nullptr) {
        cur = match;
        sub_chosen =
            match->get_subcommands([](const CLI::App* a) { return !a->get_name().empty(); })
                .empty();
        continue;
      }
      // A word where a subcommand goes: a typo, unless this level takes
      // positional values of its own.
      bool has_positional = false;
      for (const CLI::Option* o : cur->get_options({}))
        has_positional = has_positional || o->get_positional();
      if (has_positional) continue;
      const std::string near = nearest(arg, names);
      std::string known;
      for (const auto& n : names)
        known += (known.empty() ? "" : ", ") + n;
      return "unknown subcommand '" + arg + "'" +
             (near.empty() ? "" : "; did you mean '" + near + "'?") + " (known: " + known + ")";
    }
  }
  return {};
}

/// The check before CLI11 parses, for a program's main(): 0 when every word
/// is known; else prints the error the way CLI11 prints its own and returns
/// CLI11's exit code for unexpected arguments.
///   if (const int rc = tsmh::cli_words::check_words(app, argc, argv)) return rc;
inline int check_words(const CLI::App& app, int argc, const char* const* argv) {
  const std::string bad = unknown_word(app, argc, argv);
  if (bad.empty()) return 0;
  std::cerr << bad << "\nRun with --help for more information.\n";
  return static_cast<int>(CLI::ExitCodes::ExtrasError);
}

}  // namespace tsmh::cli_words
