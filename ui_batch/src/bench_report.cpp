// `vproto bench`'s report: DIR/report.html (and the same as DIR/report.md) from bench.json,
// one log-log work-precision plot per solver family, drawn with vproto's own plotter.
#include <sys/utsname.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <thread>

#include "cli_support.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/plot.h"

namespace vproto::ui_batch::detail {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

// One accuracy knob swept: per point its setting, its cost and its error.
struct Sweep {
  std::string label;
  std::vector<double> knob, seconds, error;
};

// A solver family: its sweeps against one reference.
struct Family {
  std::string id, title, knob, reference;
  std::vector<Sweep> sweeps;
};

// a row's number by key, or by JSON pointer ("/calculix/seconds"); NaN when absent
double number(const json& row, const char* key) {
  if (key[0] == '/') {
    const json::json_pointer at(key);
    return row.contains(at) && row[at].is_number() ? row[at].get<double>() : NAN;
  }
  return row.contains(key) && row[key].is_number() ? row[key].get<double>() : NAN;
}

// the sweep of `rows` (an array of objects): knob, cost and |error| by key, rows kept by
// `keep`
Sweep sweep_of(const std::string& label, const json& rows, const char* knob, const char* cost,
               const char* error, const std::function<bool(const json&)>& keep = {}) {
  Sweep s;
  s.label = label;
  if (!rows.is_array()) return s;
  for (const json& r : rows) {
    if (keep && !keep(r)) continue;
    if (!std::isfinite(number(r, cost))) continue;  // (a peer that did not run)
    s.knob.push_back(number(r, knob));
    s.seconds.push_back(number(r, cost));
    s.error.push_back(std::abs(number(r, error)));
  }
  return s;
}

std::vector<Family> families(const json& b) {
  std::vector<Family> out;
  const json none;
  auto at = [&](std::initializer_list<const char*> path) -> const json& {
    const json* j = &b;
    for (const char* k : path) {
      if (!j->is_object() || !j->contains(k)) return none;
      j = &(*j)[k];
    }
    return *j;
  };
  out.push_back({"csg",
                 "CSG: the 49-hole plate",
                 "segments per hole",
                 "volume of round holes (the faceting error)",
                 {sweep_of("batched difference", at({"csg", "segments_sweep"}), "segments",
                           "seconds", "volume_relative_error")}});
  Family statics{"fe_static",
                 "FE statics: cantilever tip deflection",
                 "mesh size (m)",
                 "CalculiX C3D10 on a converged mesh, 3.043e-4 m (references.md)",
                 {}};
  for (const char* element : {"tet4", "tet10"}) {
    auto is = [&](const json& r) { return r.value("element", "") == element; };
    statics.sweeps.push_back(sweep_of(std::string("vproto ") + element,
                                      at({"elastic", "static_cantilever"}), "mesh_size", "seconds",
                                      "tip_relative_error", is));
    statics.sweeps.push_back(
        sweep_of(std::string("CalculiX ") + element, at({"elastic", "static_cantilever"}),
                 "mesh_size", "/calculix/calculix_seconds", "/calculix/tip_relative_error", is));
  }
  out.push_back(statics);
  out.push_back(
      {"fe_frequency",
       "FE modes: cantilever first frequency",
       "mesh size (m)",
       "Euler-Bernoulli f1 (a model error of about 0.1 % for this section remains)",
       {sweep_of("vproto tet10, subspace iteration", at({"elastic", "first_frequency"}),
                 "mesh_size", "seconds", "relative_error_vs_euler_bernoulli"),
        sweep_of("CalculiX tet10, *FREQUENCY", at({"elastic", "first_frequency"}), "mesh_size",
                 "/calculix/seconds", "/calculix/relative_error_vs_euler_bernoulli")}});
  Family newmark{"newmark",
                 "Newmark: period error of the cantilever's first mode",
                 "omega h",
                 "the mode's exact period (error (w h)^2 / 12 predicted)",
                 {}};
  {
    Sweep s = sweep_of("period error", at({"elastic", "newmark"}), "omega_h", "seconds_per_step",
                       "period_error");
    const json& rows = at({"elastic", "newmark"});
    for (std::size_t k = 0; k < s.seconds.size() && rows.is_array(); ++k)
      s.seconds[k] *= number(rows[k], "steps");  // the run's cost, not a step's
    newmark.sweeps.push_back(s);
  }
  out.push_back(newmark);
  out.push_back({"newmark_tolerance",
                 "Newmark through the engine's step rule: simulate(tolerance=...) with no dt",
                 "tolerance",
                 "the same mesh's first frequency; KE + SE - f.u = 0 for a load applied at once",
                 {sweep_of("period error", at({"elastic", "newmark_tolerance"}), "tolerance",
                           "seconds", "period_error"),
                  sweep_of("energy error / f.u", at({"elastic", "newmark_tolerance"}), "tolerance",
                           "seconds", "energy_error")}});
  out.push_back({"paw",
                 "Snap-fit paw pushed over its catch (quasistatic, mu = 0.3)",
                 "mesh size (in), or the increment at 0.1 in",
                 "CalculiX C3D10 with contact on the same meshes (bench/calculix_paw.py)",
                 {sweep_of("sliding force vs ccx 0.05 in", at({"paw", "mesh_sweep"}), "mesh_in",
                           "seconds", "sliding_error_vs_calculix_0.05in"),
                  sweep_of("sliding force vs ccx, same h", at({"paw", "mesh_sweep"}), "mesh_in",
                           "seconds", "sliding_difference"),
                  sweep_of("push 0.26 in, increments", at({"paw", "increment_sweep"}),
                           "increment_in", "seconds", "push_difference")}});
  out.push_back(
      {"rigid",
       "Rigid bodies: torque-free tumbling (Dzhanibekov) over 5 s",
       "time step (s)",
       "a 16 times finer run",
       {sweep_of("angular velocity", at({"rigid"}), "time_step", "seconds", "omega_error"),
        sweep_of("energy drift", at({"rigid"}), "time_step", "seconds", "energy_drift")}});
  out.push_back({"pendulum",
                 "Joints: a pendulum released horizontal (revolute, RATTLE)",
                 "time step (s)",
                 "the exact large-amplitude period 4 sqrt(I / (m g d)) K(sin 45 deg)",
                 {sweep_of("period", at({"pendulum"}), "time_step", "seconds", "period_error"),
                  sweep_of("energy drift / (m g d)", at({"pendulum"}), "time_step", "seconds",
                           "energy_drift")}});
  out.push_back({"contact",
                 "Contact: a ball's bounce",
                 "time step (s)",
                 "the rebound height e^2 h and the impact time sqrt(2 h / g)",
                 {sweep_of("rebound height", at({"contact", "bounce"}), "time_step", "seconds",
                           "rebound_relative_error"),
                  sweep_of("impact time", at({"contact", "bounce"}), "time_step", "seconds",
                           "impact_time_error")}});
  return out;
}

std::string fmt(double v) {
  if (!std::isfinite(v)) return "-";
  char s[32];
  std::snprintf(s, sizeof s, "%.3g", v);
  return s;
}

std::string html_escape(const std::string& t) {
  std::string out;
  for (char c : t) {
    if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '&')
      out += "&amp;";
    else
      out += c;
  }
  return out;
}

// the figures that are not sweeps: leaf values under `j`, as "path: value" rows
void flatten(const json& j, const std::string& path,
             std::vector<std::pair<std::string, std::string>>* rows) {
  if (j.is_object()) {
    for (const auto& [k, v] : j.items()) flatten(v, path.empty() ? k : path + "." + k, rows);
  } else if (j.is_array()) {
    for (std::size_t k = 0; k < j.size(); ++k)
      flatten(j[k], path + "[" + std::to_string(k) + "]", rows);
  } else if (j.is_number()) {
    rows->push_back({path, fmt(j.get<double>())});
  } else if (j.is_string()) {
    rows->push_back({path, j.get<std::string>()});
  } else if (j.is_boolean()) {
    rows->push_back({path, j.get<bool>() ? "true" : "false"});
  }
}

// a table in both forms (a "|" in a cell would split a Markdown row: it is escaped)
void write_table(const std::vector<std::string>& header,
                 const std::vector<std::vector<std::string>>& rows, std::ostream& html,
                 std::ostream& md) {
  auto row = [&](const std::vector<std::string>& cells, const char* tag) {
    html << "<tr>";
    md << "|";
    for (const std::string& cell : cells) {
      html << "<" << tag << ">" << html_escape(cell) << "</" << tag << ">";
      std::string text = cell;
      for (std::size_t at = text.find('|'); at != std::string::npos; at = text.find('|', at + 2))
        text.replace(at, 1, "\\|");
      md << " " << text << " |";
    }
    html << "</tr>\n";
    md << "\n";
  };
  html << "<table>";
  row(header, "th");
  md << "|";
  for (std::size_t k = 0; k < header.size(); ++k) md << "---|";
  md << "\n";
  for (const auto& cells : rows) row(cells, "td");
  html << "</table>\n";
  md << "\n";
}

std::string run_text(const std::string& command) {
  std::string out;
  if (FILE* p = ::popen(command.c_str(), "r")) {
    char buf[256];
    while (std::fgets(buf, sizeof buf, p)) out += buf;
    ::pclose(p);
  }
  while (!out.empty() && (out.back() == '\n' || out.back() == ' ')) out.pop_back();
  return out;
}

}  // namespace

json machine_description() {
  json m;
  std::string model;
  std::ifstream cpu("/proc/cpuinfo");
  for (std::string line; std::getline(cpu, line);)
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  m["cpu"] = model.empty() ? "unknown" : model;
  m["cores"] = std::thread::hardware_concurrency();
  std::ifstream mem("/proc/meminfo");
  for (std::string line; std::getline(mem, line);)
    if (line.rfind("MemTotal:", 0) == 0) {
      m["memory_gb"] = std::strtod(line.c_str() + 9, nullptr) / (1024.0 * 1024.0);
      break;
    }
  struct utsname u {};
  if (::uname(&u) == 0) m["os"] = std::string(u.sysname) + " " + u.release;
  return m;
}

std::string source_commit() {
#ifdef VPROTO_SOURCE_DIR
  const std::string dir = VPROTO_SOURCE_DIR;
  const std::string head = run_text("git -C '" + dir + "' rev-parse --short=12 HEAD 2>/dev/null");
  if (head.empty()) return "unknown";
  const std::string dirty =
      run_text("git -C '" + dir + "' status --porcelain --untracked-files=no 2>/dev/null");
  return dirty.empty() ? head : head + " (with uncommitted changes)";
#else
  return "unknown";
#endif
}

void write_bench_report(const json& b, const fs::path& out) {
  fs::create_directories(out / "plots");
  std::ostringstream html, md;
  const json machine = b.value("machine", json::object());
  const std::string when = run_text("date -u '+%Y-%m-%d %H:%M UTC'");
  const std::string where = machine.value("cpu", std::string("unknown")) + ", " +
                            std::to_string(machine.value("cores", 0)) + " cores, " +
                            fmt(machine.value("memory_gb", 0.0)) + " GB, " +
                            machine.value("os", std::string(""));
  const std::string commit = b.value("commit", std::string("unknown"));
  html << "<!doctype html>\n<html><head><meta charset=\"utf-8\"><title>vproto bench</title>\n"
       << "<style>body{font-family:sans-serif;max-width:1000px;margin:2em auto;color:#222}"
          "table{border-collapse:collapse;margin:0.5em 0 1.5em}td,th{border:1px solid #ccc;"
          "padding:3px 8px;text-align:right}th{background:#f2f2f2}td:first-child,th:first-child"
          "{text-align:left}img{max-width:100%}</style></head><body>\n"
       << "<h1>vproto bench</h1>\n<p>" << html_escape(when) << " &middot; commit <code>"
       << html_escape(commit) << "</code> &middot; " << html_escape(where) << " &middot; "
       << (b.value("quick", false) ? "quick sweep" : "full sweep") << ", "
       << fmt(b.value("total_seconds", 0.0)) << " s in all</p>\n"
       << "<p>Each plot is a solver family's work against precision: its accuracy knob swept, "
          "the error against an independent reference over the run time (log-log, lower left "
          "is better). The data is bench.json.</p>\n";
  md << "# vproto bench\n\n"
     << when << " · commit `" << commit << "` · " << where << " · "
     << (b.value("quick", false) ? "quick sweep" : "full sweep") << ", "
     << fmt(b.value("total_seconds", 0.0)) << " s in all\n\n"
     << "Each plot is a solver family's work against precision: error against an independent "
        "reference over the run time (log-log). The data is bench.json.\n\n";

  for (const Family& f : families(b)) {
    std::vector<PlotSeries> series;
    bool any = false;
    for (std::size_t k = 0; k < f.sweeps.size(); ++k) {
      PlotSeries s;
      s.label = f.sweeps[k].label;
      s.x = f.sweeps[k].seconds;
      s.y = f.sweeps[k].error;
      s.colour = series_colour(static_cast<int>(k));
      s.markers = true;
      any = any || !s.x.empty();
      series.push_back(std::move(s));
    }
    if (!any) continue;
    PlotOptions po;
    po.title = f.title;
    po.x_label = "run time (s)";
    po.y_label = "relative error";
    po.log_x = po.log_y = true;
    const std::string file = "plots/" + f.id + ".png";
    write_line_plot(series, po, (out / file).string());
    html << "<h2>" << html_escape(f.title) << "</h2>\n<p>Reference: " << html_escape(f.reference)
         << ".</p>\n<img src=\"" << file << "\" alt=\"" << html_escape(f.title) << "\">\n";
    md << "## " << f.title << "\n\nReference: " << f.reference << ".\n\n![" << f.title << "]("
       << file << ")\n\n";
    std::vector<std::vector<std::string>> points;
    for (const Sweep& sw : f.sweeps)
      for (std::size_t k = 0; k < sw.seconds.size(); ++k)
        points.push_back({sw.label, fmt(sw.knob[k]), fmt(sw.seconds[k]), fmt(sw.error[k])});
    write_table({"series", f.knob, "seconds", "relative error"}, points, html, md);
  }

  // the skips, each with and without
  if (b.contains("skips") && !b["skips"].empty()) {
    std::vector<std::vector<std::string>> skip_rows;
    for (const json& r : b["skips"])
      skip_rows.push_back({r.value("skip", std::string()), r.value("input", std::string()),
                           fmt(r.value("seconds_with", NAN)), fmt(r.value("seconds_without", NAN)),
                           r["speedup"].is_number() && std::isfinite(r["speedup"].get<double>())
                               ? fmt(r["speedup"].get<double>()) + "x"
                               : std::string("all of it"),
                           std::string(r.value("same_result", false) ? "yes: " : "NO: ") +
                               r.value("check", std::string())});
    const std::string intro =
        "What the engine skips when a scene does not need it: the same work with the skip and "
        "without it, and the check that the answer is the same.";
    html << "<h2>Skips, measured</h2>\n<p>" << html_escape(intro) << "</p>\n";
    md << "## Skips, measured\n\n" << intro << "\n\n";
    write_table({"skip", "input", "seconds with", "seconds without", "saves", "same result"},
                skip_rows, html, md);
  }

  // the solver backends: the same answers on every FE sample
  if (b.contains("solvers") && b["solvers"].contains("agreement")) {
    std::vector<std::vector<std::string>> solver_rows;
    for (const json& r : b["solvers"]["agreement"])
      solver_rows.push_back(
          {r.value("sample", std::string()), r.value("what", std::string()),
           fmt(r.value("cholmod_seconds", NAN)), fmt(r.value("petsc_seconds", NAN)),
           r.value("petsc_method", std::string()), fmt(r.value("max_relative_difference", NAN)),
           r.value("worst_column", std::string())});
    const std::string intro =
        "Each FE sample run with --solver cholmod and --solver petsc (one process): the "
        "largest difference of their history.csv, each column over its own largest value.";
    html << "<h2>Solver backends</h2>\n<p>" << html_escape(intro) << "</p>\n";
    md << "## Solver backends\n\n" << intro << "\n\n";
    write_table({"sample", "what", "cholmod s", "petsc s", "petsc method", "max difference",
                 "worst column"},
                solver_rows, html, md);
  }

  // the other figures: speeds and single-point checks, as measured
  std::vector<std::pair<std::string, std::string>> rows;
  if (b.contains("solvers")) {
    for (const char* key : {"static_vs_calculix", "ranks"})
      if (b["solvers"].contains(key))
        flatten(b["solvers"][key], std::string("solvers.") + key, &rows);
  }
  for (const char* key : {"render", "contact", "snapfit"})
    if (b.contains(key)) flatten(b[key], key, &rows);
  if (b.contains("csg")) {
    flatten(b["csg"]["case"], "csg.case", &rows);
    flatten(b["csg"]["seconds"], "csg.seconds", &rows);
    flatten(b["csg"]["volume_relative_error"], "csg.volume_relative_error", &rows);
  }
  std::vector<std::vector<std::string>> figures;
  for (const auto& [k, v] : rows) figures.push_back({k, v});
  html << "<h2>Other figures</h2>\n";
  md << "## Other figures\n\n";
  write_table({"figure", "value"}, figures, html, md);

  // the stress suite, when `vproto bench --stress` wrote to the same folder
  if (fs::exists(out / "stress.json")) {
    try {
      const json stress = json::parse(std::ifstream(out / "stress.json"));
      std::vector<std::vector<std::string>> scenes;
      for (const json& r : stress["scenes"])
        scenes.push_back(
            {r.value("scene", std::string()), r.value("pushes", std::string()),
             std::to_string(r.value("exit", 0)),
             r.value("correct", false) ? "as required" : "NOT: " + r.value("why", std::string()),
             fmt(r.value("seconds", 0.0))});
      html << "<h2>Stress scenes</h2>\n<p>" << stress["scenes"].size() << " scenes, "
           << stress.value("failed", 0) << " not as required.</p>\n";
      md << "## Stress scenes\n\n"
         << stress["scenes"].size() << " scenes, " << stress.value("failed", 0)
         << " not as required.\n\n";
      write_table({"scene", "pushes", "exit", "verdict", "seconds"}, scenes, html, md);
    } catch (const std::exception&) {
      // an unreadable stress.json is left out of the report
    }
  }
  // peers, pair by pair on the same meshes
  std::vector<std::vector<std::string>> peer_rows;
  const json empty = json::array();
  const json& statics_rows = b.contains("elastic") && b["elastic"].contains("static_cantilever")
                                 ? b["elastic"]["static_cantilever"]
                                 : empty;
  for (const json& r : statics_rows) {
    if (!r.contains("calculix") || !r["calculix"].contains("calculix_seconds")) continue;
    const json& c = r["calculix"];
    peer_rows.push_back(
        {"static " + r.value("element", std::string()) + ", h " + fmt(r.value("mesh_size", 0.0)),
         std::to_string(r.value("dofs", 0L)), fmt(r.value("seconds", 0.0)),
         fmt(c.value("calculix_seconds", 0.0)),
         fmt(r.value("seconds", 0.0) / c.value("calculix_seconds", 1.0)),
         fmt(r.value("tip_relative_error", 0.0)), fmt(c.value("tip_relative_error", 0.0)),
         fmt(c.value("max_relative_difference", 0.0))});
  }
  const json& frequency_rows = b.contains("elastic") && b["elastic"].contains("first_frequency")
                                   ? b["elastic"]["first_frequency"]
                                   : empty;
  for (const json& r : frequency_rows) {
    if (!r.contains("calculix")) continue;
    const json& c = r["calculix"];
    peer_rows.push_back({"f1 tet10, h " + fmt(r.value("mesh_size", 0.0)),
                         std::to_string(r.value("dofs", 0L)), fmt(r.value("seconds", 0.0)),
                         fmt(c.value("seconds", 0.0)),
                         fmt(r.value("seconds", 0.0) / c.value("seconds", 1.0)),
                         fmt(r.value("relative_error_vs_euler_bernoulli", 0.0)),
                         fmt(c.value("relative_error_vs_euler_bernoulli", 0.0)),
                         fmt(std::abs(c.value("relative_difference", 0.0)))});
  }
  html << "<h2>Peers</h2>\n";
  md << "## Peers\n\n";
  if (!peer_rows.empty()) {
    const std::string intro =
        "CalculiX (ccx, 2 threads) on the very meshes vproto solved, with the same clamp and "
        "nodal loads. Times: ccx's whole run, vproto's assembly and solve; the ratio is "
        "vproto's over ccx's. Errors against the references above; the last column is the "
        "largest nodal displacement difference (or the frequencies' difference), relative.";
    html << "<p>" << html_escape(intro) << "</p>\n";
    md << intro << "\n\n";
    write_table({"case", "dofs", "vproto s", "ccx s", "time ratio", "vproto error", "ccx error",
                 "difference"},
                peer_rows, html, md);
  } else {
    const std::string missing =
        "CalculiX is not installed: apt-get install calculix-ccx puts it side by side with "
        "vproto here, on the same meshes.";
    html << "<p>" << html_escape(missing) << "</p>\n";
    md << missing << "\n\n";
  }
  // the plate in the CSG tools
  if (b.contains("csg") && b["csg"].contains("peers")) {
    const json& csg = b["csg"];
    std::vector<std::vector<std::string>> csg_rows = {
        {"vproto (CGAL corefinement, batched)", fmt(csg.value("seconds", NAN)), "1",
         fmt(csg.value("volume_relative_error", NAN))}};
    for (const auto& [tool, r] : csg["peers"].items()) {
      if (r.contains("seconds"))
        csg_rows.push_back({tool, fmt(r["seconds"].get<double>()),
                            fmt(csg.value("seconds", NAN) / r["seconds"].get<double>()),
                            fmt(r.value("volume_relative_error", NAN))});
      else
        csg_rows.push_back(
            {tool, "-", "-", r.value("skipped", r.value("error", std::string("not run")))});
    }
    const std::string intro =
        "The 49-hole plate (64 segments per hole) in the CSG tools a designer would otherwise "
        "use, on this machine; the ratio is vproto's time over the tool's.";
    html << "<p>" << html_escape(intro) << "</p>\n";
    md << intro << "\n\n";
    write_table({"tool", "seconds", "time ratio", "volume error"}, csg_rows, html, md);
  }
  const std::string more =
      "Contact: bench/calculix_paw.py runs the snap-fit paw against CalculiX with contact "
      "(figures in docs/paw_calculix.md; about 30 minutes).";
  html << "<p>" << html_escape(more) << "</p>\n</body></html>\n";
  md << more << "\n";
  write_text_atomically(out / "report.html", html.str());
  write_text_atomically(out / "report.md", md.str());
}

}  // namespace vproto::ui_batch::detail
