#pragma once
// Private to ui_batch: what the vproto commands share (options, progress, loading,
// build.json).

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <functional>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "vproto/modeler/compiler.h"
#include "vproto/modeler/evaluator.h"
#include "vproto/sim/elastic_contact.h"
#include "vproto/sim/static_solve.h"
#include "vproto/ui_batch/animation_writer.h"
#include "vproto/ui_batch/vtu_writer.h"

namespace vproto::ui_batch::detail {

using Clock = std::chrono::steady_clock;

extern const char kUsage[];
extern const SourceLoc kCommandLine;

struct Options {
  std::string command;
  std::string file;
  std::string out_dir;
  std::string format = "stl";
  bool tets = false;
  bool convex = false;
  bool quiet = false;
  bool help = false;
  bool quick = false;   ///< bench --quick
  bool stress = false;  ///< bench --stress
  std::vector<modeler::ParamOverride> overrides;
  std::string render_file;  ///< build --render FILE.png
  // run
  std::optional<int> frames;
  std::optional<std::pair<int, int>> size;
  bool no_render = false;
  std::optional<std::string> export_format;
  std::optional<std::string> mode;
  std::optional<std::string> solver;  ///< auto | cholmod | petsc
  std::vector<std::string> outputs;   ///< sweep --output KEY (summary.json paths)
  std::string cache_dir;              ///< the compile cache (default DIR/.vproto-cache)
  bool rank_writes = false;  ///< under mpirun, this rank writes its own DIR (a sweep's variant)
  std::optional<double> duration;
  std::optional<double> dt;
  /// Not on the command line: `vproto bench` turns a skip off to measure it (every elastic
  /// body meshed, loaded or not).
  bool mesh_every_elastic_body = false;
};

/// Parses the command line (everything after `vproto`); throws InputError.
Options parse_args(const std::vector<std::string>& args);

// Progress on stderr: on a terminal one bar that redraws itself (stage, percent, rate,
// time left); otherwise one line per stage, so logs stay readable.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet)
      : err_(err), quiet_(quiet), tty_(&err == &std::cerr && ::isatty(2)), start_(Clock::now()) {}
  ~Progress() { finish(); }

  void stage(const std::string& what) { update(what, -1, 0); }

  /// `done` of `total` work items finished (-1: a stage without a count).
  void update(const std::string& what, int done, int total) {
    if (quiet_) return;
    const double t = std::chrono::duration<double>(Clock::now() - start_).count();
    char head[32];
    std::snprintf(head, sizeof head, "[%7.2fs] ", t);
    if (!tty_) {
      // one line per stage: repeated updates of the same stage are not logged
      if (what == last_) return;
      last_ = what;
      err_ << "vproto: " << head << what << "\n" << std::flush;
      return;
    }
    std::string line = "vproto: " + std::string(head);
    if (done >= 0 && total > 0) {
      const double frac = static_cast<double>(done) / total;
      const int width = 20, filled = static_cast<int>(frac * width);
      line += "[" + std::string(filled, '#') + std::string(width - filled, '.') + "] ";
      char stats[96];
      const double rate = t > 0 ? done / t : 0;
      if (done > 0 && done < total)
        std::snprintf(stats, sizeof stats, "%3.0f%% %.1f/s ~%.0fs left ", 100 * frac, rate,
                      (total - done) / rate);
      else
        std::snprintf(stats, sizeof stats, "%3.0f%% ", 100 * frac);
      line += stats;
    }
    line += what;
    err_ << "\r\033[K" << line << std::flush;
    open_line_ = true;
  }

  void finish() {
    if (open_line_) err_ << "\n" << std::flush;
    open_line_ = false;
  }

 private:
  std::ostream& err_;
  bool quiet_;
  bool tty_;
  bool open_line_ = false;
  std::string last_;
  Clock::time_point start_;
};

/// Seconds since `t`.
double since(Clock::time_point t);

/// Reads, parses and evaluates the script; prints its warnings unless quiet.
modeler::EvaluatedScript load(const Options& o, Progress& progress, std::ostream& err);

/// Writes DIR/build.json for compiled bodies.
void write_build_json(const std::filesystem::path& out, const Options& o,
                      const modeler::EvaluatedScript& script, const modeler::CompileReport& report,
                      double parse_seconds, double export_seconds, Clock::time_point start);

nlohmann::json vec_json(const Eigen::Vector3d& v);

/// An elastic body's stress and strain peaks into its summary.json entry `body`
/// (docs/contracts.md: peak_von_mises, peak_strain, their _time and _at,
/// away_from_contact, and yield when the material gives yield_strength or yield_strain).
void add_material_peaks(const sim::Body& body, const sim::MaterialPeaks& peaks,
                        nlohmann::json* entry);

/// The point arrays an elastic body's exported volume mesh carries beside its displacement:
/// `von_mises` and `strain` (nodal averages), and `yield_ratio` (sim::yield_ratios) when its
/// material gives a yield.
std::vector<PointField> vtu_fields(const sim::Body& body, const Eigen::VectorXd& von_mises,
                                   const Eigen::VectorXd& strain);

/// The warning's sentence for a body that passed its material's yield: where, when, and
/// what to change (away from contacts linear elasticity does not hold past it; only
/// under a contact, a sharp edge or corner concentrates it at the elements' scale).
std::string yield_sentence(const sim::Body& body, const sim::MaterialPeaks& peaks);

/// DIR/contact_steps.csv (docs/contracts.md): one row per elastic body and step whose contact
/// stage solved rows: what it solved (points found, solved, pressed, sliding; passes,
/// Newton iterations, sweeps) and where its time went (new compliance columns, Delassus
/// assembly, the solves, the whole stage), so a run's contact cost can be read step by step.
std::string contact_steps_csv(const sim::Scene& scene,
                              const std::vector<sim::ContactStepRecord>& records);

/// What a finished (or failed) run reports in summary.json.
struct RunReport {
  std::string status = "ok";
  std::string mode;
  std::string note;    ///< optional
  std::string reason;  ///< why it failed, when it did
  long steps = 0;
  double sim_time = 0;
  double time_step = 0;  ///< 0 when the run has none
  std::string time_step_reason;
  double build_seconds = 0;
  double simulate_seconds = 0;
  Clock::time_point start;
  nlohmann::json probes = nlohmann::json::object();
  nlohmann::json bodies = nlohmann::json::array();
  double kinetic_energy = 0, strain_energy = 0, external_work = 0, dissipated = 0;
  double mesh_seconds = 0, assemble_seconds = 0, factor_seconds = 0;
  /// Of `simulate_seconds`: elastic contact (detection, compliance columns, Delassus
  /// assembly, solves); written only when the run has elastic contact.
  double contact_seconds = 0;
  nlohmann::json solver;  ///< per FE body: ordering, nnz(L), flops (optional)
  nlohmann::json extra = nlohmann::json::object();       ///< further top-level figures
  nlohmann::json wall_extra = nlohmann::json::object();  ///< further `wall_time` stages
};

/// A ParaView series: one VTU per elastic body per exported frame (the volume mesh at its
/// deformed place with point data), and DIR/meshes/series.pvd naming them all.
class VtuSeries {
 public:
  explicit VtuSeries(std::filesystem::path out_dir) : dir_(std::move(out_dir) / "meshes") {}
  /// u: nodal displacements (#N by 3); `fields` go along after `displacement`.
  void add(const sim::Body& body, int body_index, int frame, double time, const Eigen::MatrixX3d& u,
           const std::vector<PointField>& fields);
  /// Writes series.pvd (when any file was written).
  void finish();
  /// Wall time spent writing the files so far, s.
  double seconds() const { return seconds_; }

 private:
  std::filesystem::path dir_;
  double seconds_ = 0;
  struct Entry {
    double time;
    int part;
    std::string file;
  };
  std::vector<Entry> entries_;
};

/// summary.json's `solver` record of one FE body: which backend ran and why, and what
/// its factor or iterations cost.
nlohmann::json solver_json(const sim::SolverStats& stats, Eigen::Index dofs);

/// Writes DIR/summary.json.
void write_summary(const std::filesystem::path& out, const RunReport& report,
                   const AnimationStats& stats);

/// This machine: CPU model, cores, memory (from /proc), and the OS.
nlohmann::json machine_description();
/// The source tree's commit (git, at run time; "unknown" outside a checkout).
std::string source_commit();
/// DIR/report.html and DIR/report.md from bench.json's figures: a log-log plot per solver
/// family (error against seconds) in DIR/plots/, the tables, the machine and the commit;
/// DIR/stress.json's table when a stress run wrote one there.
void write_bench_report(const nlohmann::json& bench, const std::filesystem::path& out);

int command_run(const Options& o, std::ostream& err);
int command_bench(const Options& o, std::ostream& err);
int command_sweep(const Options& o, std::ostream& err);

/// Runs a command and maps its exceptions to cli.md's exit codes, the message to `err`.
int guarded(std::ostream& err, const std::function<int()>& body);
/// The command `o` names, guarded.
int run_guarded(const Options& o, std::ostream& err);
/// `vproto bench --stress`: the stress scenes; exit 3 when one did not go as required.
int command_stress(const Options& o, std::ostream& err);

/// The static branch of `run`: given the solutions, writes frames (the load ramped from 0 to 1),
/// meshes, summary.json and history.csv into `out`.
int run_static(const Options& o, const sim::Scene& scene,
               const std::vector<sim::ElasticSolution>& solutions, double solve_seconds,
               const std::filesystem::path& out, Progress& progress, Clock::time_point start,
               double build_seconds, double mesh_seconds, std::ostream& err);

}  // namespace vproto::ui_batch::detail
