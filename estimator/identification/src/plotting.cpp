#include "estimator/plotting.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "files/file_size_limit.hpp"

namespace tsmh::estimator {
namespace {

namespace fs = std::filesystem;

// Starts gnuplot with `args`, stdout and stderr to `log`. Returns its pid, or
// -1 when it could not be started.
pid_t start_gnuplot(const std::vector<std::string>& args, const fs::path& log,
                    const fs::path& cwd = {}) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  // Scripts name their files relative to their own directory, so a copied
  // report directory can be redrawn.
  if (!cwd.empty()) posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> argv;
  for (const auto& a : args)
    argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, "gnuplot", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  return rc == 0 ? pid : -1;
}

// The exit status of a started gnuplot, or -1 (not started, or killed).
int wait_gnuplot(pid_t pid) {
  if (pid < 0) return -1;
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// gnuplot string literal (single quotes; a quote is doubled).
std::string quoted(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    out += c;
    if (c == '\'') out += '\'';
  }
  return out + "'";
}

std::string extension(const std::string& terminal) {
  return terminal == "svg" ? ".svg" : ".png";
}

std::string terminal_line(const std::string& terminal, int w, int h) {
  if (terminal == "svg")
    return "set terminal svg size " + std::to_string(w) + "," + std::to_string(h) +
           " dynamic noenhanced background rgb 'white'\n";
  // noenhanced: names such as low_speed print as written, not as subscripts.
  return "set terminal pngcairo size " + std::to_string(w) + "," + std::to_string(h) +
         " noenhanced font ',10'\n";
}

// The blocks of validation samples as [t_begin, t_end] intervals, for shading.
std::vector<std::pair<double, double>> validation_spans(const FitData& d) {
  std::vector<std::pair<double, double>> spans;
  bool open = false;
  for (std::size_t i = 0; i < d.size(); ++i) {
    const bool v = d.role[i] == SampleRole::kValidation;
    if (v && !open) spans.push_back({d.motion[i].t, d.motion[i].t});
    if (v) spans.back().second = d.motion[i].t;
    open = v;
  }
  return spans;
}

}  // namespace

std::string plot_terminal() {
  const fs::path log = fs::temp_directory_path() /
                       ("tsm-gnuplot-probe-" + std::to_string(static_cast<long>(getpid())));
  const int rc = wait_gnuplot(start_gnuplot({"gnuplot", "-e", "set terminal pngcairo"}, log));
  std::error_code ec;
  fs::remove(log, ec);
  return rc == 0 ? "pngcairo" : "svg";
}

std::string run_gnuplot(const std::vector<fs::path>& scripts) {
  // Side by side: each script draws its own image from files it only reads.
  std::vector<std::pair<pid_t, fs::path>> running;
  for (const auto& script : scripts) {
    const fs::path abs = fs::absolute(script);
    const fs::path log = fs::path(abs).replace_extension(".log");
    running.emplace_back(
        start_gnuplot({"gnuplot", abs.filename().string()}, log, abs.parent_path()), log);
  }
  std::string err;
  for (std::size_t k = 0; k < running.size(); ++k) {
    const auto& [pid, log] = running[k];
    const int rc = wait_gnuplot(pid);
    if (err.empty() && pid < 0) {
      err = "gnuplot could not be started (install gnuplot-nox: scripts/deps.sh)";
    } else if (err.empty() && rc != 0) {
      std::string msg = read_text(log);
      if (msg.size() > 400) msg = msg.substr(msg.size() - 400);
      err = "gnuplot failed on " + scripts[k].filename().string() + ": " + msg;
    }
    std::error_code ec;
    fs::remove(log, ec);
  }
  return err;
}

std::string run_gnuplot(const fs::path& script) {
  return run_gnuplot(std::vector<fs::path>{script});
}

namespace {

// Plot data and scripts are part of the output folder: a write that fails
// part way (disk full, a file-size limit) is an error of the run, never a
// warning that leaves a truncated file to be committed.
void write_or_throw(const fs::path& path, const std::function<void(std::ostream&)>& write) {
  errno = 0;
  std::ofstream f(path);
  if (f) write(f);
  f.flush();
  if (f) f.close();
  if (!f) {
    const int err = errno;
    const std::string why = err != 0 ? std::string(" (") + std::strerror(err) + ")" : "";
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    const bool limit = files::hit_file_size_limit(err, ec ? 0 : size);
    fs::remove(path, ec);
    if (limit) throw std::runtime_error(files::file_size_limit_message(path.string()));
    throw std::runtime_error(path.string() + ": write failed" + why);
  }
}

// Whatever went wrong in gnuplot, no partial image stays behind; an image
// that gnuplot reported as made but is cut short (no PNG IEND chunk, no
// closing </svg>) turns the outcome into an error.
void check_images(const fs::path& dir, const std::vector<std::string>& images, std::string& error) {
  std::error_code ec;
  for (const auto& name : images) {
    const fs::path p = dir / name;
    if (!error.empty()) {
      fs::remove(p, ec);
      continue;
    }
    std::ifstream in(p, std::ios::binary);
    std::string tail;
    if (in) {
      in.seekg(0, std::ios::end);
      const auto size = static_cast<long>(in.tellg());
      const long n = std::min(16L, std::max(0L, size));
      in.seekg(size - n);
      tail.resize(static_cast<std::size_t>(n));
      if (!in.read(tail.data(), n)) tail.clear();
    }
    const bool complete = name.ends_with(".png")   ? tail.find("IEND") != std::string::npos
                          : name.ends_with(".svg") ? tail.find("</svg>") != std::string::npos
                                                   : !tail.empty();
    if (!complete) error = p.string() + ": the image is missing or cut short";
  }
  if (!error.empty())
    for (const auto& name : images)
      fs::remove(dir / name, ec);
}

// The terminal gnuplot draws with, and its images' file extension.
struct Terminal {
  std::string name = plot_terminal();
  std::string ext = extension(name);
};

// Writes each gnuplot script, runs them side by side, and reports the images
// when every one was drawn whole; else the error, with no image left behind.
PlotOutcome render(const fs::path& dir,
                   const std::vector<std::pair<fs::path, std::string>>& scripts,
                   std::vector<std::string> images) {
  std::vector<fs::path> paths;
  for (const auto& [path, text] : scripts) {
    write_or_throw(path, [&](std::ostream& f) { f << text; });
    paths.push_back(path);
  }
  PlotOutcome out;
  out.error = run_gnuplot(paths);
  check_images(dir, images, out.error);
  if (out.error.empty()) out.files = std::move(images);
  return out;
}

// The residual measured - `friction` as the line a pixel-wide plot draws:
// for each of `columns` equal time bins, its smallest and largest sample in
// the order they occur. A line through them covers each column from its
// minimum to its maximum, as the full line does, while cairo strokes 2 points
// a column instead of ~30 overlapping full-height segments (a 40 s residual
// took 0.7 s of gnuplot's CPU, more than the rest of the report).
std::vector<std::pair<double, double>> residual_envelope(const FitData& d,
                                                         std::span<const double> friction,
                                                         std::size_t columns) {
  std::vector<std::pair<double, double>> out;
  if (d.size() == 0 || columns == 0) return out;
  const double t0 = d.motion.front().t;
  const double span = std::max(d.duration(), 1e-12);
  std::size_t lo = 0, hi = 0, bin = 0;
  bool open = false;
  const auto residual = [&](std::size_t i) { return d.measured[i] - friction[i]; };
  const auto flush = [&] {
    if (!open) return;
    out.push_back({d.motion[std::min(lo, hi)].t, residual(std::min(lo, hi))});
    if (lo != hi) out.push_back({d.motion[std::max(lo, hi)].t, residual(std::max(lo, hi))});
  };
  for (std::size_t i = 0; i < d.size(); ++i) {
    if (!std::isfinite(residual(i))) continue;
    const auto b = std::min(columns - 1, static_cast<std::size_t>(static_cast<double>(columns) *
                                                                  (d.motion[i].t - t0) / span));
    if (!open || b != bin) {
      flush();
      lo = hi = i;
      bin = b;
      open = true;
    }
    if (residual(i) < residual(lo)) lo = i;
    if (residual(i) > residual(hi)) hi = i;
  }
  flush();
  return out;
}

}  // namespace

PlotOutcome plot_friction(const fs::path& dir, const std::string& prefix, const FitData& data,
                          const std::vector<PlotCurve>& curves, const std::string& title) {
  const Terminal term;
  // The data file: at most ~20000 rows, so a 40 s record keeps 2 ms detail.
  const std::size_t stride = std::max<std::size_t>(1, data.size() / 20000);
  const fs::path dat = dir / (prefix + "_plot_data.csv");
  write_or_throw(dat, [&](std::ostream& f) {
    f << "# t, xd, measured";
    for (const auto& c : curves)
      f << ", " << c.title;
    f << "\n";
    f.precision(7);
    for (std::size_t i = 0; i < data.size(); i += stride) {
      f << data.motion[i].t << "," << data.motion[i].xd << "," << data.measured[i];
      for (const auto& c : curves)
        f << "," << c.friction[i];
      f << "\n";
    }
  });
  // The residual plot's own data: each curve's residual envelope
  // (residual_envelope), one gnuplot data set per curve (`index`).
  constexpr int kResidualWidth = 1400;
  const fs::path res_dat = dir / (prefix + "_residual_data.csv");
  write_or_throw(res_dat, [&](std::ostream& f) {
    f.precision(7);
    for (std::size_t c = 0; c < curves.size(); ++c) {
      f << (c ? "\n\n" : "") << "# t, measured - " << curves[c].title
        << " (smallest and largest per pixel column)\n";
      for (const auto& [t, r] : residual_envelope(data, curves[c].friction, kResidualWidth))
        f << t << "," << r << "\n";
    }
  });
  std::ostringstream shade;
  for (const auto& [a, b] : validation_spans(data)) {
    shade << "set object rect from " << a << ", graph 0 to " << b
          << ", graph 1 fc rgb '#eeeeee' fs solid 1.0 noborder behind\n";
  }
  const std::string common = "set datafile separator ','\nset grid\nset key outside right top\n";
  const auto image = [&](const std::string& name) { return prefix + "_" + name + term.ext; };

  // One script per image, so the three gnuplots run side by side.
  std::ostringstream friction, hysteresis, residual;
  // 1. friction over time
  friction << common << terminal_line(term.name, 1400, 600) << "set output "
           << quoted(image("friction")) << "\nset title "
           << quoted(title + ": friction over time (validation blocks shaded)")
           << "\nset xlabel 't (s)'\nset ylabel 'F (N)'\n"
           << shade.str() << "plot " << quoted(dat.filename().string())
           << " using 1:3 with lines lw 1 lc rgb '#999999' title 'measured'";
  for (std::size_t c = 0; c < curves.size(); ++c)
    friction << ", '' using 1:" << 4 + c << " with lines lw 1.5 title " << quoted(curves[c].title);
  friction << "\n";
  // 2. hysteresis loops: friction vs velocity
  hysteresis << common << terminal_line(term.name, 900, 700) << "set output "
             << quoted(image("hysteresis")) << "\nset title "
             << quoted(title + ": friction vs velocity (hysteresis loops)")
             << "\nset xlabel 'xd (rad/s)'\nset ylabel 'F (N)'\n"
             << "plot " << quoted(dat.filename().string())
             << " using 2:3 with dots lc rgb '#999999' title 'measured'";
  for (std::size_t c = 0; c < curves.size(); ++c)
    hysteresis << ", '' using 2:" << 4 + c << " with lines lw 1 title " << quoted(curves[c].title);
  hysteresis << "\n";
  // 3. residuals, on the scale of the scored samples: the warm-up (the model
  // starts at rest, the joint may not) is clipped instead of stretching the axis.
  double scored_max = 0.0;
  for (std::size_t i = 0; i < data.size(); ++i)
    if (data.role[i] != SampleRole::kIgnored)
      for (const auto& c : curves)
        if (std::isfinite(c.friction[i]))
          scored_max = std::max(scored_max, std::fabs(data.measured[i] - c.friction[i]));
  residual << common << terminal_line(term.name, kResidualWidth, 500) << "set output "
           << quoted(image("residual")) << "\nset title "
           << quoted(title + ": residual, measured - model (validation shaded; warm-up clipped)")
           << "\nset xlabel 't (s)'\nset ylabel 'error (N)'\n";
  if (scored_max > 0.0)
    residual << "set yrange [" << -1.1 * scored_max << ":" << 1.1 * scored_max << "]\n";
  residual << shade.str() << "plot ";
  for (std::size_t c = 0; c < curves.size(); ++c) {
    residual << (c ? ", " : "") << quoted(res_dat.filename().string()) << " index " << c
             << " using 1:2 with lines lw 1 title " << quoted(curves[c].title);
  }
  residual << "\n";
  const auto script = [&](const std::string& name) { return dir / (prefix + "_" + name + ".gp"); };
  return render(dir,
                {{script("friction"), friction.str()},
                 {script("hysteresis"), hysteresis.str()},
                 {script("residual"), residual.str()}},
                {image("friction"), image("hysteresis"), image("residual")});
}

PlotOutcome plot_regimes(const fs::path& dir, const std::string& prefix, const RegimeBars& bars,
                         const std::string& title) {
  const Terminal term;
  const fs::path dat = dir / (prefix + "_regimes.csv");
  write_or_throw(dat, [&](std::ostream& f) {
    f << "regime";
    for (const auto& s : bars.series)
      f << "," << s;
    f << "\n";
    for (std::size_t r = 0; r < bars.regimes.size(); ++r) {
      f << bars.regimes[r];
      for (std::size_t s = 0; s < bars.series.size(); ++s)
        f << "," << bars.rmse[s][r];
      f << "\n";
    }
  });
  std::ostringstream s;
  s << "set datafile separator ','\n"
    << terminal_line(term.name, 1200, 500) << "set output "
    << quoted(prefix + "_regimes" + term.ext) << "\nset title " << quoted(title)
    << "\nset style data histograms\nset style histogram clustered gap 1\n"
    << "set style fill solid 0.8 border -1\nset ylabel 'validation RMSE (N)'\n"
    << "set xtics rotate by -35\nset grid ytics\nset key outside right top\n"
    << "plot " << quoted(dat.filename().string()) << " using 2:xtic(1) title columnhead";
  for (std::size_t k = 1; k < bars.series.size(); ++k)
    s << ", '' using " << 2 + k << " title columnhead";
  s << "\n";
  return render(dir, {{dir / (prefix + "_regimes.gp"), s.str()}}, {prefix + "_regimes" + term.ext});
}

PlotOutcome plot_xy(const fs::path& dir, const std::string& name,
                    const std::vector<std::pair<double, double>>& points, const std::string& xlabel,
                    const std::string& ylabel, const std::string& title) {
  const Terminal term;
  const fs::path dat = dir / (name + ".csv");
  write_or_throw(dat, [&](std::ostream& f) {
    f << "x,y\n";
    for (const auto& [x, y] : points)
      f << x << "," << y << "\n";
  });
  std::ostringstream s;
  s << "set datafile separator ','\n"
    << terminal_line(term.name, 900, 500) << "set output " << quoted(name + term.ext)
    << "\nset title " << quoted(title) << "\nset xlabel " << quoted(xlabel) << "\nset ylabel "
    << quoted(ylabel) << "\nset grid\nset key off\nplot " << quoted(dat.filename().string())
    << " using 1:2 every ::1 with points pt 7 ps 0.4\n";
  return render(dir, {{dir / (name + ".gp"), s.str()}}, {name + term.ext});
}

}  // namespace tsmh::estimator
