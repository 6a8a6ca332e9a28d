// vproto sweep: a design sweep. One full `vproto run` per combination of the --set value
// lists, the compile cache shared, spread over the MPI ranks when mpirun launched it (each
// rank runs whole variants of its own, with solves of its own); then one table
// (DIR/sweep.csv, DIR/sweep.json) and plots (DIR/plots/sweep_*.png) of chosen
// summary.json figures against the parameters.

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli_support.h"
#include "vproto/materials/errors.h"
#include "vproto/sim/linear_solver.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/plot.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using modeler::ParamOverride;
using nlohmann::json;

constexpr std::size_t kMaxVariants = 1000;

// "a,b,[1, 2],c": commas outside brackets and parentheses separate the values
std::vector<std::string> split_values(const std::string& name, const std::string& text) {
  std::vector<std::string> out;
  std::string cur;
  int depth = 0;
  for (char c : text) {
    if (c == '[' || c == '(') ++depth;
    if (c == ']' || c == ')') --depth;
    if (c == ',' && depth == 0) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  for (const std::string& v : out)
    if (v.find_first_not_of(" \t") == std::string::npos)
      throw InputError(kCommandLine, "--set " + name + "=" + text +
                                         ": an empty value in the list; give values "
                                         "separated by commas, e.g. --set " +
                                         name + "=1mm,2mm,3mm");
  return out;
}

// a file-system-safe name for a variant: "clearance=0.002in_hook_angle=30deg"
std::string label_of(const std::vector<ParamOverride>& values) {
  std::string label;
  for (const ParamOverride& v : values) {
    if (!label.empty()) label += "_";
    label += v.name + "=" + v.expression;
  }
  for (char& c : label)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '=' || c == '.' || c == '-' ||
          c == '_'))
      c = '~';
  return label;
}

// summary.json at a dotted path: objects by key, arrays by index or by an element's "name"
const json* at_path(const json& doc, const std::string& path) {
  const json* j = &doc;
  std::stringstream parts(path);
  for (std::string key; std::getline(parts, key, '.');) {
    if (j->is_object()) {
      if (!j->contains(key)) return nullptr;
      j = &(*j)[key];
    } else if (j->is_array()) {
      const json* found = nullptr;
      char* end = nullptr;
      const long k = std::strtol(key.c_str(), &end, 10);
      if (end && *end == '\0' && k >= 0 && static_cast<std::size_t>(k) < j->size())
        found = &(*j)[static_cast<std::size_t>(k)];
      for (const json& e : *j)
        if (!found && e.is_object() && e.value("name", std::string()) == key) found = &e;
      if (!found) return nullptr;
      j = found;
    } else {
      return nullptr;
    }
  }
  return j;
}

// What a design sweep usually compares, where the run has it: the insertion and reaction
// curves' peaks (a drive's peak push and pull: the insertion and retention forces), the peak
// contact force, each body's peak stress and reaction and its ratios to the yield away from
// contacts and sharp corners, the probes' displacements and the run's time.
std::vector<std::string> default_outputs(const json& s) {
  std::vector<std::string> out;
  for (const char* curves : {"insertion_curves", "reaction_curves"})
    if (s.contains(curves) && s[curves].is_object())
      for (const auto& [body, c] : s[curves].items())
        for (const auto& [key, v] : c.items())  // peak, peak_push (insertion), peak_pull
          if (key.rfind("peak", 0) == 0 && v.is_number())
            out.push_back(std::string(curves) + "." + body + "." + key);
  if (s.contains("peak_contact_force")) out.push_back("peak_contact_force");
  if (s.contains("bodies"))
    for (const json& b : s["bodies"]) {
      const std::string name = "bodies." + b.value("name", std::string());
      for (const char* key : {"peak_von_mises", "peak_reaction"})
        if (b.contains(key)) out.push_back(name + "." + key);
      // how near the yield the part comes in its body (away from contacts and sharp inside
      // corners, where linear-elastic peaks grow with refinement), and at those corners as
      // extrapolated from their faces: a snap-fit arm's root
      for (const char* where : {"away_from_contact_and_corners", "sharp_corner_hot_spot"})
        if (b.contains("yield") && b["yield"].contains(where))
          for (const auto& [key, v] : b["yield"][where].items())
            if (key.find("_ratio") != std::string::npos && v.is_number())
              out.push_back(name + ".yield." + where + "." + key);
    }
  if (s.contains("probes"))
    for (const auto& [probe, p] : s["probes"].items())
      if (p.contains("u"))
        for (int k = 0; k < 3; ++k) out.push_back("probes." + probe + ".u." + std::to_string(k));
  out.push_back("wall_time.total");
  return out;
}

// the SI value of a parameter as the run evaluated it (build.json: "0.00254 (SI, ...)")
double si_value(const fs::path& run_dir, const std::string& name) {
  try {
    const json b = json::parse(std::ifstream(run_dir / "build.json"));
    const std::string text = b.at("params").at(name).get<std::string>();
    char* end = nullptr;
    const double v = std::strtod(text.c_str(), &end);
    return end != text.c_str() ? v : NAN;
  } catch (const std::exception&) {
    return NAN;
  }
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string q = "\"";
  for (char c : text) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

std::string number_text(double v) {
  if (!std::isfinite(v)) return "";
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

}  // namespace

int command_sweep(const Options& o, std::ostream& err) {
  if (o.file.empty())
    throw InputError(kCommandLine, "sweep needs a script: vproto sweep FILE -o DIR --set NAME=a,b");
  if (o.out_dir.empty()) throw InputError(kCommandLine, "sweep needs an output folder: -o DIR");
  if (o.overrides.empty())
    throw InputError(kCommandLine,
                     "sweep needs at least one --set NAME=a,b,c: the values to sweep");
  // the lists, and their combinations (the first --set outermost)
  std::vector<std::pair<std::string, std::vector<std::string>>> lists;
  std::size_t total = 1;
  for (const ParamOverride& p : o.overrides) {
    for (const auto& l : lists)
      if (l.first == p.name)
        throw InputError(kCommandLine, "--set " + p.name +
                                           " is given twice; give all its values in one list: "
                                           "--set " +
                                           p.name + "=a,b,c");
    lists.emplace_back(p.name, split_values(p.name, p.expression));
    total *= lists.back().second.size();
    if (total > kMaxVariants)
      throw InputError(kCommandLine, "the sweep has more than " + std::to_string(kMaxVariants) +
                                         " combinations; sweep fewer values at a time");
  }
  std::vector<std::vector<ParamOverride>> variants(total);
  for (std::size_t i = 0; i < total; ++i) {
    std::size_t rest = i;
    for (std::size_t l = lists.size(); l-- > 0;) {
      const auto& values = lists[l].second;
      variants[i].insert(variants[i].begin(), {lists[l].first, values[rest % values.size()]});
      rest /= values.size();
    }
  }
  Progress progress(err, o.quiet);
  // every variant's script must evaluate before any runs (a bad value stops the sweep
  // with its place, nothing written)
  for (const auto& v : variants) {
    Options check = o;
    check.command = "check";
    check.overrides = v;
    std::ostringstream quiet;
    Progress silent(quiet, true);
    try {
      (void)load(check, silent, quiet);
    } catch (const InputError& e) {
      throw InputError(e.loc(), e.message() + " (in the sweep's variant " + label_of(v) + ")");
    }
  }
  const fs::path out(o.out_dir);
  const fs::path runs = out / "runs";
  std::error_code ec;
  fs::create_directories(runs, ec);
  if (ec || ::access(runs.c_str(), W_OK) != 0)
    throw InputError(SourceLoc{o.out_dir, 0, 0}, "cannot write to the output folder");

  // this rank's share: variants i with i mod ranks == rank, each solved by this rank alone
  const int rank = sim::launched_rank(), ranks = sim::launched_ranks();
  sim::share_solves_among_ranks(false);
  for (std::size_t i = 0; i < total; ++i) {
    if (static_cast<int>(i % static_cast<std::size_t>(ranks)) != rank) continue;
    Options r = o;
    r.command = "run";
    r.overrides = variants[i];
    r.out_dir = (runs / label_of(variants[i])).string();
    r.cache_dir = (out / ".vproto-cache").string();
    r.rank_writes = true;
    r.quiet = true;
    r.outputs.clear();
    progress.stage("variant " + std::to_string(i + 1) + " of " + std::to_string(total) + ": " +
                   label_of(variants[i]) +
                   (ranks > 1 ? " (rank " + std::to_string(rank) + ")" : ""));
    std::ostringstream messages;
    const auto t0 = Clock::now();
    const int code = run_guarded(r, messages);
    const json status = {{"exit", code}, {"message", messages.str()}, {"seconds", since(t0)}};
    fs::create_directories(r.out_dir, ec);
    write_text_atomically(fs::path(r.out_dir) / "sweep_status.json", status.dump(1) + "\n");
  }
  sim::parallel_barrier();
  sim::share_solves_among_ranks(true);
  sim::mark_ranks_finished_together();
  if (rank != 0) return 0;

  // rank 0: the table
  std::vector<json> summaries(total), statuses(total);
  for (std::size_t i = 0; i < total; ++i) {
    const fs::path dir = runs / label_of(variants[i]);
    try {
      statuses[i] = json::parse(std::ifstream(dir / "sweep_status.json"));
    } catch (const std::exception&) {
      statuses[i] = {{"exit", 1}, {"message", "no status: the variant did not run"}};
    }
    if (statuses[i].value("exit", 1) == 0) {
      try {
        summaries[i] = json::parse(std::ifstream(dir / "summary.json"));
      } catch (const std::exception&) {
        statuses[i] = {{"exit", 1}, {"message", "summary.json unreadable"}};
      }
    }
  }
  std::vector<std::string> outputs = o.outputs;
  if (outputs.empty())
    for (const json& s : summaries)
      if (!s.is_null()) {
        outputs = default_outputs(s);
        break;
      }
  std::ostringstream csv;
  for (const auto& l : lists) csv << csv_cell(l.first) << "," << csv_cell(l.first + "_si") << ",";
  csv << "exit,seconds";
  for (const std::string& k : outputs) csv << "," << csv_cell(k);
  csv << "\n";
  json table = json::array();
  std::vector<std::vector<double>> si(total), values(total);
  int worst = 0;
  std::size_t failed = 0;
  std::string first_failure;
  for (std::size_t i = 0; i < total; ++i) {
    const fs::path dir = runs / label_of(variants[i]);
    json row = {{"run", dir.string()}};
    for (const ParamOverride& v : variants[i]) {
      const double x = si_value(dir, v.name);
      si[i].push_back(x);
      row["params"][v.name] = v.expression;
      row["params_si"][v.name] = std::isfinite(x) ? json(x) : json();
      csv << csv_cell(v.expression) << "," << number_text(x) << ",";
    }
    const int code = statuses[i].value("exit", 1);
    row["exit"] = code;
    row["seconds"] = statuses[i].value("seconds", 0.0);
    if (code != 0) {
      row["message"] = statuses[i].value("message", std::string());
      worst = std::max(worst, code);
      if (failed++ == 0)
        first_failure = label_of(variants[i]) + ": " + row["message"].get<std::string>();
    }
    csv << code << "," << number_text(statuses[i].value("seconds", 0.0));
    for (const std::string& k : outputs) {
      const json* v = summaries[i].is_null() ? nullptr : at_path(summaries[i], k);
      const double x = v && v->is_number() ? v->get<double>() : NAN;
      values[i].push_back(x);
      row["outputs"][k] = std::isfinite(x) ? json(x) : json();
      csv << "," << number_text(x);
    }
    csv << "\n";
    table.push_back(row);
  }
  write_text_atomically(out / "sweep.csv", csv.str());
  json parameters = json::object();
  for (const auto& l : lists) parameters[l.first] = l.second;
  write_text_atomically(out / "sweep.json", json{{"script", o.file},
                                                 {"parameters", parameters},
                                                 {"outputs", outputs},
                                                 {"variants", table},
                                                 {"failed", failed}}
                                                    .dump(1) +
                                                "\n");
  // plots: each output against the first parameter, one line per combination of the others
  bool numeric_x = true;
  for (const auto& row : si) numeric_x = numeric_x && std::isfinite(row[0]);
  if (numeric_x && !outputs.empty()) {
    fs::create_directories(out / "plots", ec);
    const std::size_t inner = lists[0].second.size(), groups = total / inner;
    for (std::size_t k = 0; k < outputs.size() && k < 8; ++k) {
      std::vector<PlotSeries> series;
      for (std::size_t g = 0; g < groups; ++g) {
        PlotSeries s;
        s.markers = true;
        s.colour = series_colour(static_cast<int>(g));
        for (std::size_t i = 0; i < total; ++i) {
          // the variants whose other parameters are the g-th combination
          std::size_t rest = i, index = 0, scale = 1;
          for (std::size_t l = lists.size(); l-- > 0;) {
            const std::size_t n = lists[l].second.size();
            if (l != 0) {
              index += (rest % n) * scale;
              scale *= n;
            }
            rest /= n;
          }
          if (index != g) continue;
          if (s.label.empty()) {
            for (std::size_t l = 1; l < lists.size(); ++l)
              s.label +=
                  (l > 1 ? ", " : "") + variants[i][l].name + "=" + variants[i][l].expression;
            if (s.label.empty()) s.label = outputs[k];
          }
          s.x.push_back(si[i][0]);
          s.y.push_back(values[i][k]);
        }
        series.push_back(std::move(s));
      }
      PlotOptions po;
      po.title = fs::path(o.file).filename().string() + ": " + outputs[k];
      po.x_label = lists[0].first + " (SI)";
      po.y_label = outputs[k];
      std::string name = outputs[k];
      for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
      write_line_plot(series, po, (out / "plots" / ("sweep_" + name + ".png")).string());
    }
  }
  progress.stage("done: " + std::to_string(total) + " variants (" + std::to_string(failed) +
                 " failed) -> " + (out / "sweep.csv").string());
  progress.finish();
  if (failed > 0) {
    err << "vproto: sweep: " << failed << " of " << total
        << " variants failed (their rows in sweep.csv say why); the first: " << first_failure;
    return worst;
  }
  return 0;
}

}  // namespace vproto::ui_batch::detail
