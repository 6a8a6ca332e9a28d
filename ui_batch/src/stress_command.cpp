// `vproto bench --stress [--quick] -o DIR`: scenes that push the numerics, each run as a
// user would (`vproto run`, in-process) and checked against what must happen: the right
// figure (against an analytic value), or a clean refusal (exit 2) or stop (exit 3) whose
// message names the cause. Never NaN or Inf in the outputs, a crash or a silently wrong
// figure. Writes DIR/stress.json and DIR/stress.md (a table).
#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>

#include "cli_support.h"
#include "vproto/ui_batch/atomic_file.h"
#include "vproto/ui_batch/cli.h"

namespace vproto::ui_batch::detail {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using History = std::vector<std::map<std::string, double>>;

History read_history(const fs::path& file) {
  History rows;
  std::ifstream in(file);
  std::string line;
  if (!std::getline(in, line)) return rows;
  std::vector<std::string> names;
  std::stringstream head(line);
  for (std::string cell; std::getline(head, cell, ',');) names.push_back(cell);
  while (std::getline(in, line)) {
    std::map<std::string, double> row;
    std::stringstream cells(line);
    std::size_t k = 0;
    for (std::string cell; std::getline(cells, cell, ',') && k < names.size(); ++k)
      row[names[k]] = std::strtod(cell.c_str(), nullptr);
    rows.push_back(std::move(row));
  }
  return rows;
}

// what a finished run left: its summary, build report and history
struct Outcome {
  json summary, build;
  History history;
};

// A check returns "" when the figure is right, else what is wrong with it.
using Check = std::function<std::string(const Outcome&)>;

struct Scene {
  std::string name, pushes;
  std::string script;
  std::vector<std::string> args;  ///< after `run FILE -o DIR`
  int exit_code = 0;              ///< 0: runs; 2: refused; 3: stopped
  std::string message;            ///< part of the message (refusals and stops)
  Check check;                    ///< for runs that finish
  std::string environment;        ///< NAME=VALUE set for the run
  bool quick = true;
  /// Sets the stage in the scene's folder (its `@DIR@` in the script) before the run: the
  /// returned object is held until the run ends (a lock another run holds)
  std::function<std::shared_ptr<void>(const fs::path& dir)> prepare;
};

std::string within(const char* what, double value, double expected, double tolerance) {
  if (std::abs(value - expected) <= tolerance) return "";
  std::ostringstream s;
  s << what << " " << value << ", expected " << expected << " within " << tolerance;
  return s.str();
}

// a body's mass from build.json
double mass_of(const Outcome& o, const std::string& body) {
  for (const auto& b : o.build["bodies"])
    if (b["name"] == body) return b["mass"].get<double>();
  return std::nan("");
}

// the largest |E - E0| over the run of kinetic energy plus the bodies' weight times height
double worst_energy_change(const Outcome& o, const std::vector<std::string>& bodies) {
  double worst = 0, first = std::nan("");
  for (const auto& row : o.history) {
    double e = row.at("kinetic_energy") + row.at("strain_energy");
    for (const auto& b : bodies) e += mass_of(o, b) * 9.81 * row.at(b + "_z");
    if (std::isnan(first)) first = e;
    worst = std::max(worst, std::abs(e - first));
  }
  return worst;
}

// every number in the outputs is finite (nlohmann writes NaN and Inf as null)
bool all_finite(const json& j) {
  if (j.is_null()) return false;
  if (j.is_number()) return std::isfinite(j.get<double>());
  if (j.is_structured())
    for (const auto& item : j) {
      if (!all_finite(item)) return false;
    }
  return true;
}

const char* kFloor =
    "rigid body floor (material=steel) { translate([-2, -2, -0.2]) box([4, 4, 0.2]); }\n"
    "fix floor;\n";

// the first contact event at `expected` seconds
Check lands_at(double expected, double tolerance) {
  return [=](const Outcome& o) {
    if (o.summary["events"].empty()) return std::string("it never landed");
    return within("landing time (s)", o.summary["events"][0]["t"], expected, tolerance);
  };
}

Scene runs(std::string name, std::string pushes, std::string script, Check check) {
  Scene s;
  s.name = std::move(name);
  s.pushes = std::move(pushes);
  s.script = std::move(script);
  s.check = std::move(check);
  return s;
}

Scene refused(std::string name, std::string pushes, std::string script, std::string message,
              std::string environment = "") {
  Scene s;
  s.name = std::move(name);
  s.pushes = std::move(pushes);
  s.script = std::move(script);
  s.exit_code = 2;
  s.message = std::move(message);
  s.environment = std::move(environment);
  return s;
}

std::vector<Scene> scenes() {
  std::vector<Scene> s;
  // --- energy and the integrators ---
  s.push_back(runs("restitution one", "an elastic bounce: no energy may be lost or made",
                   std::string(kFloor) +
                       "rigid body cube (material=steel) { translate([-0.05, -0.05, 0.15]) "
                       "box(0.1); }\ngravity [0, 0, -9.81];\ncontact restitution=1 friction=0;\n"
                       "simulate(duration=1s, dt=1ms, frames=3);\n",
                   [](const Outcome& o) {
                     return within("dissipated energy (J)", o.summary["energy"]["dissipated"], 0,
                                   1e-6);
                   }));
  s.push_back(runs("horizontal pendulum", "a 90-degree swing for 10 s at dt 1 ms: energy kept",
                   "units length=mm;\nrigid body bar (material=steel) { translate([0, -10, -10]) "
                   "box([500, 20, 20]); }\njoint revolute bar at=[0, 0, 0] axis=[0, 1, 0];\n"
                   "gravity [0, 0, -9.81m/s^2];\nsimulate(duration=10s, dt=1ms, frames=3);\n",
                   [](const Outcome& o) {
                     const double mgd = mass_of(o, "bar") * 9.81 * 0.25;
                     return within("energy change / m g d", worst_energy_change(o, {"bar"}) / mgd,
                                   0, 1e-4);
                   }));
  s.push_back(runs(
      "spherical chain of ten", "a long joint chain released sideways",
      [] {
        std::string t = "units length=mm;\ngravity [0, 0, -9.81m/s^2];\n";
        for (int k = 0; k < 10; ++k) {
          t += "rigid body l" + std::to_string(k) + " (material=steel) { translate([" +
               std::to_string(100 * k) + ", -5, -5]) box([100, 10, 10]); }\n";
          t += "joint spherical l" + std::to_string(k) +
               (k ? " to l" + std::to_string(k - 1) : std::string()) + " at=[" +
               std::to_string(100 * k) + ", 0, 0];\n";
        }
        for (int k = 0; k + 1 < 10; ++k)
          for (int q = k + 1; q < 10; ++q)
            t += "nocontact l" + std::to_string(k) + " l" + std::to_string(q) + ";\n";
        return t + "simulate(duration=2s, dt=1ms, frames=3);\n";
      }(),
      [](const Outcome& o) {
        std::vector<std::string> links;
        double m = 0;
        for (int k = 0; k < 10; ++k) {
          links.push_back("l" + std::to_string(k));
          m += mass_of(o, links.back());
        }
        if (!(o.summary["max_joint_drift"].get<double>() < 1e-9))
          return std::string("joint drift ") + o.summary["max_joint_drift"].dump();
        return within("energy change / (m g L)", worst_energy_change(o, links) / (m * 9.81 * 1.0),
                      0, 1e-3);
      }));
  // --- contact ---
  // a block on a 30-degree incline: without friction it slides at g sin(theta) (0.306 m
  // in 0.5 s), with friction 10 it is held
  for (const double mu : {0.0, 10.0})
    s.push_back(
        runs(mu == 0 ? "frictionless incline" : "friction ten on an incline",
             mu == 0 ? "a block sliding at g sin(theta)" : "a block held by very high friction",
             "rigid body ramp (material=steel) { rotate([0, -30, 0]) translate([-1, -1, -0.1]) "
             "box([2, 2, 0.1]); }\nfix ramp;\nrigid body b (material=steel) { rotate([0, -30, "
             "0]) translate([-0.05, -0.05, 0]) box(0.1); }\ngravity [0, 0, -9.81];\n"
             "contact friction=" +
                 std::to_string(mu) + ";\nsimulate(duration=0.5s, dt=1ms, frames=3);\n",
             [mu](const Outcome& o) {
               const auto& a = o.history.front();
               const auto& z = o.history.back();
               const double d = std::hypot(z.at("b_x") - a.at("b_x"), z.at("b_z") - a.at("b_z"));
               return mu == 0 ? within("distance slid (m)", d, 0.5 * 9.81 * 0.5 * 0.25, 1e-3)
                              : within("distance slid (m)", d, 0, 1e-7);
             }));
  s.push_back(runs(
      "mass ratio 1e4 stack", "a 1e4 times heavier box resting on a light one",
      std::string(kFloor) +
          "material feather { E = 1GPa; nu = 0.3; density = 1kg/m^3; }\n"
          "material lead { E = 1GPa; nu = 0.3; density = 10000kg/m^3; }\n"
          "rigid body light (material=feather) { translate([-0.05, -0.05, 0]) box(0.1); "
          "}\nrigid body heavy (material=lead) { translate([-0.05, -0.05, 0.1]) "
          "box(0.1); }\ngravity [0, 0, -9.81];\nsimulate(duration=1s, dt=1ms, "
          "frames=3);\n",
      [](const Outcome& o) {
        const std::string sink =
            within("heavy box's centre (m)", o.history.back().at("heavy_z"), 0.15, 1e-6);
        return sink.empty()
                   ? within("kinetic energy (J)", o.history.back().at("kinetic_energy"), 0, 1e-6)
                   : sink;
      }));
  s.push_back(
      runs("fast box at a thin wall", "100 m/s against a 1 mm wall at dt 1 ms",
           "rigid body wall (material=steel) { translate([0.5, -1, -1]) box([0.001, 2, 2]); "
           "}\nfix wall;\nrigid body b (material=steel) { translate([-0.05, -0.05, -0.05]) "
           "box(0.1); }\nvelocity b linear=[100, 0, 0];\ncontact restitution=0;\n"
           "simulate(duration=0.05s, dt=1ms, frames=3);\n",
           [](const Outcome& o) {
             const double x = o.history.back().at("b_x");
             return x <= 0.5 - 0.05 + 1e-6 ? std::string()
                                           : "the box went into the wall: x = " + std::to_string(x);
           }));
  s.push_back(runs("micrometre box drop", "a 10 um box falling 10 um: units and tolerances scale",
                   "units length=um;\nrigid body floor (material=steel) { translate([-100, -100, "
                   "-10]) box([200, 200, 10]); }\nfix floor;\nrigid body b (material=steel) { "
                   "translate([-5, -5, 10]) box(10); }\ngravity [0, 0, -9.81m/s^2];\n"
                   "simulate(duration=3ms, dt=1us, frames=3);\n",
                   lands_at(std::sqrt(2 * 10e-6 / 9.81), 2e-6)));
  s.push_back(runs("kilometre box drop", "a 1 km box falling 10 m",
                   "rigid body floor (material=steel) { translate([-10000, -10000, -1000]) "
                   "box([20000, 20000, 1000]); }\nfix floor;\nrigid body b (material=steel) { "
                   "translate([-500, -500, 10]) box(1000); }\ngravity [0, 0, -9.81];\n"
                   "simulate(duration=2s, dt=1ms, frames=3);\n",
                   lands_at(std::sqrt(2 * 10 / 9.81), 2e-3)));
  // the same drop at steps two decades apart: the impact is located at the instant
  for (const char* dt : {"10ms", "0.1ms"})
    s.push_back(runs(std::string("drop at dt ") + dt, "the impact time, whatever the step",
                     std::string(kFloor) +
                         "rigid body b (material=steel) { translate([-0.05, -0.05, 0.5]) "
                         "box(0.1); }\ngravity [0, 0, -9.81];\ncontact restitution=0.5;\n"
                         "simulate(duration=0.4s, dt=" +
                         dt + ", frames=3);\n",
                     lands_at(std::sqrt(2 * 0.5 / 9.81), 1e-6)));
  // --- elastic bodies ---
  s.push_back(
      runs("rubber ball dropped", "an elastic body nothing holds lands: energy never grows",
           "units length=mm;\nmaterial rubber { E = 10MPa; nu = 0.45; density = "
           "1100kg/m^3; friction = 0.5; }\n" +
               std::string("rigid body slab (material=steel) { translate([-100, -100, -20]) "
                           "box([200, 200, 20]); }\nfix slab;\nelastic body ball "
                           "(material=rubber, mesh_size=10mm, element=tet4, segments=16) { "
                           "translate([0, 0, 35]) sphere(r=25); }\ngravity [0, 0, "
                           "-9.81m/s^2];\nsimulate(duration=0.2s, frames=3);\n"),
           [](const Outcome& o) {
             if (o.summary["events"].empty()) return std::string("it never landed");
             return o.summary["energy"]["dissipated"].get<double>() >= -1e-9
                        ? std::string()
                        : "energy made: dissipated " + o.summary["energy"]["dissipated"].dump();
           }));
  s.push_back(
      runs("steel cube on a rubber pad", "a free rigid body on a clamped elastic one",
           "units length=mm;\nmaterial rubber { E = 10MPa; nu = 0.45; density = "
           "1100kg/m^3; friction = 0.5; }\nelastic body pad (material=rubber, mesh_size=5mm, "
           "element=tet4) { translate([-30, -30, 0]) box([60, 60, 10]); }\nrigid body cube "
           "(material=steel) { translate([-10, -10, 15]) box(20); }\nfix pad "
           "region=box([-100, -100, -1], [100, 100, 0.1]);\ngravity [0, 0, -9.81m/s^2];\n"
           "simulate(duration=0.15s, frames=3);\n",
           [](const Outcome& o) {
             const double w = (mass_of(o, "pad") + mass_of(o, "cube")) * 9.81;
             return within("clamp reaction / weights", o.history.back().at("pad_rz") / w, 1, 1e-4);
           }));
  // --- more motion with exact answers ---
  s.push_back(runs("slider pushed", "a block on a slider pushed by 10 N: x = F t^2 / 2m",
                   "rigid body b (material=steel) { translate([-0.05, -0.05, -0.05]) box(0.1); "
                   "}\njoint slider b axis=[1, 0, 0];\nforce b [10, 3, 7];\ngravity [0, 0, "
                   "-9.81];\nsimulate(duration=1s, dt=1ms, frames=3);\n",
                   [](const Outcome& o) {
                     const double x = o.history.back().at("b_x") - o.history.front().at("b_x");
                     const std::string along =
                         within("travel (m)", x, 0.5 * 10 / mass_of(o, "b"), 1e-9);
                     return along.empty() ? within("off the axis (m)",
                                                   std::abs(o.history.back().at("b_z")) +
                                                       std::abs(o.history.back().at("b_y")),
                                                   0, 1e-12)
                                          : along;
                   }));
  s.push_back(runs("restitution one sphere", "a ball bouncing back to its height",
                   std::string(kFloor) +
                       "rigid body ball (material=steel, segments=24) { translate([0, 0, 0.6]) "
                       "sphere(r=0.1); }\ngravity [0, 0, -9.81];\ncontact restitution=1 "
                       "friction=0;\nsimulate(duration=0.9s, dt=1ms, frames=3);\n",
                   [](const Outcome& o) {
                     double apex = 0;
                     bool bounced = false;
                     for (const auto& r : o.history) {
                       bounced = bounced || r.at("ball_z") < 0.2;
                       if (bounced) apex = std::max(apex, r.at("ball_z"));
                     }
                     return within("rebound apex / start height",
                                   apex / o.history.front().at("ball_z"), 1, 5e-3);
                   }));
  s.push_back(runs(
      "stack of five, frictionless", "boxes resting on each other without friction",
      [] {
        std::string t = kFloor;
        for (int k = 0; k < 5; ++k)
          t += "rigid body s" + std::to_string(k) +
               " (material=steel) { translate([-0.05, -0.05, " + std::to_string(0.1 * k) +
               "]) box(0.1); }\n";
        return t +
               "gravity [0, 0, -9.81];\ncontact friction=0;\n"
               "simulate(duration=1s, dt=1ms, frames=3);\n";
      }(),
      [](const Outcome& o) {
        return within("top box's centre (m)", o.history.back().at("s4_z"), 0.45, 1e-6);
      }));
  s.push_back(runs("needle", "a 1 m x 1 mm steel needle dropped tilted onto a floor at dt 1 ms",
                   std::string(kFloor) +
                       "rigid body needle (material=steel) { translate([-0.5, -0.0005, 0.2]) "
                       "rotate([0, 10, 0]) box([1, 0.001, 0.001]); }\ngravity [0, 0, -9.81];\n"
                       "contact restitution=0.5 friction=0.3;\nsimulate(duration=2s, dt=1ms, "
                       "frames=3);\n",
                   [](const Outcome& o) {
                     const double made = -o.summary["energy"]["dissipated"].get<double>();
                     return made <= 1e-9 ? std::string() : "it made " + std::to_string(made) + " J";
                   }));
  s.push_back(runs(
      "needle struck on its edge",
      "a 1 m x 1 mm needle falling steeply from 1 m at dt 1 ms: its edge strikes the floor and "
      "spins it about its axis at ~2,500 rad/s (1/500,000 of its transverse inertia)",
      std::string(kFloor) +
          "rigid body needle (material=steel) { translate([0, 0, 1]) rotate([0, 80, 0]) "
          "translate([-0.5, -0.0005, 0]) box([1, 0.001, 0.001]); }\ngravity [0, 0, -9.81];\n"
          "contact restitution=0.5 friction=0.3;\nsimulate(duration=3s, dt=1ms, frames=3);\n",
      [](const Outcome& o) {
        // no energy made at any step, and it ends lying on the floor, at rest
        double worst = 0;
        for (const auto& r : o.history)
          worst = std::max(worst, r.at("kinetic_energy") - r.at("external_work"));
        if (worst > 1e-9) return "the motion made " + std::to_string(worst) + " J";
        const std::string lying =
            within("centre height at the end (m)", o.history.back().at("needle_z"), 5e-4, 1e-6);
        return lying.empty() ? within("kinetic energy at the end (J)",
                                      o.history.back().at("kinetic_energy"), 0, 1e-12)
                             : lying;
      }));
  s.push_back(runs("elastic bar pushed in space", "a free elastic body: F / m, balanced load",
                   "elastic body bar (material=steel, mesh_size=0.01, element=tet4) { "
                   "translate([-0.1, -0.01, -0.01]) box([0.2, 0.02, 0.02]); }\nforce bar [0, "
                   "0, 100] region=box([-1, -1, -1], [1, 1, -0.0099]);\n"
                   "simulate(duration=0.01s, dt=0.1ms, frames=3);\n",
                   [](const Outcome& o) {
                     const double z = o.history.back().at("bar_z") - o.history.front().at("bar_z");
                     return within("rise / (F t^2 / 2m)",
                                   z / (0.5 * 100 * 1e-4 / mass_of(o, "bar")), 1, 0.02);
                   }));
  s.push_back(runs("64-segment sphere at rest", "a fine faceted ball resting on a slab",
                   std::string(kFloor) +
                       "rigid body ball (material=steel, segments=64) { translate([0, 0, 0.1]) "
                       "sphere(r=0.1); }\ngravity [0, 0, -9.81];\nsimulate(duration=0.5s, "
                       "dt=1ms, frames=3);\n",
                   [](const Outcome& o) {
                     // settled after its first few millimetres of fall: still over the
                     // second half of the run
                     const double half = o.history[o.history.size() / 2].at("ball_z");
                     const std::string still =
                         within("sink over the last 0.25 s (m)",
                                o.history.back().at("ball_z") - half, 0, 1e-9);
                     return still.empty() && o.summary["contact"]["unconverged_solves"] != 0
                                ? "unconverged contact solves: " +
                                      o.summary["contact"]["unconverged_solves"].dump()
                                : still;
                   }));
  // --- geometry at its edges ---
  s.push_back(runs("coincident faces", "a union of two boxes sharing a face: volume exact",
                   "rigid body b (material=steel) { box(0.1); translate([0.1, 0, 0]) box(0.1); "
                   "}\nsimulate(duration=0.01s, frames=2);\n",
                   [](const Outcome& o) {
                     return within("volume (m^3)", o.build["bodies"][0]["volume"], 2e-3, 1e-15);
                   }));
  s.push_back(runs("coarse mesh", "one tet10 across a cantilever: still a bending answer",
                   "elastic body beam (material=steel, mesh_size=0.05, element=tet10) { "
                   "box([1, 0.05, 0.05]); }\nfix beam region=box([-1, -1, -1], [0.001, 1, 1]);"
                   "\nforce beam [0, 0, -100] region=box([0.999, -1, -1], [2, 2, 2]);\n"
                   "probe tip beam point=[1, 0.025, 0.025];\nsimulate(mode=static, frames=2);\n",
                   [](const Outcome& o) {
                     // Euler-Bernoulli: F L^3 / (3 E I), I = b h^3 / 12
                     const double tip = 100 / (3 * 200e9 * 0.05 * std::pow(0.05, 3) / 12);
                     return within("tip deflection / beam theory",
                                   -o.summary["probes"]["tip"]["u"][2].get<double>() / tip, 1, 0.3);
                   }));
  s.push_back(refused("mesh too fine", "a mesh_size giving billions of tetrahedra",
                      "elastic body b (material=steel, mesh_size=0.0001) { box(1); }\nfix b "
                      "region=box([-1, -1, -1], [1, 1, 0.001]);\nsimulate(mode=static);\n",
                      "use a larger mesh_size"));
  s.push_back(refused("flat box", "a solid of zero thickness",
                      "rigid body b (material=steel) { box([1, 1, 0]); }\n", "must be positive"));
  // --- bad input: refused with exit 2, naming the place ---
  const std::string box = "rigid body b (material=steel) { box(0.1); }\n";
  s.push_back(refused("speed 1e300", "an absurd input", box + "velocity b linear=[1e300, 0, 0];\n",
                      "out of range"));
  s.push_back(refused("gravity 1e300", "an absurd input", box + "gravity [0, 0, -1e300];\n",
                      "out of range"));
  s.push_back(refused("dt 1e-9 s", "a billion steps", box + "simulate(duration=1s, dt=1e-9s);\n",
                      "more than 5000000"));
  s.push_back(refused("dt 1e-20 s", "a step below any use",
                      box + "simulate(duration=1s, dt=1e-20s);\n", "more than 5000000"));
  s.push_back(refused("duration 1e30 s", "a run for ever", box + "simulate(duration=1e30s);\n",
                      "more than 5000000"));
  s.push_back(refused("static free body under gravity", "no equilibrium",
                      box + "gravity [0, 0, -9.81];\nsimulate(mode=static);\n",
                      "gravity pulls it"));
  s.push_back(
      refused("nu 0.499", "near-incompressible material for tetrahedra",
              "material goo { E = 1MPa; nu = 0.499; density = 1000kg/m^3; }\nelastic body g "
              "(material=goo, mesh_size=0.05) { box(0.2); }\nfix g region=box([-1, -1, -1], "
              "[1, 1, 0.001]);\nsimulate(mode=static);\n",
              "too close to 0.5"));
  {
    // issue 13: outputs of two runs mixed in one folder
    Scene locked = refused("folder held by another run",
                           "a second run into a folder a first run is writing to", box,
                           "another vproto run is writing to this folder");
    locked.prepare = [](const fs::path& dir) -> std::shared_ptr<void> {
      fs::create_directories(dir / "out");
      const int fd = ::open((dir / "out" / ".vproto.lock").c_str(), O_RDWR | O_CREAT, 0644);
      if (fd < 0 || ::flock(fd, LOCK_EX | LOCK_NB) != 0) return nullptr;
      return std::shared_ptr<void>(nullptr, [fd](void*) { ::close(fd); });
    };
    s.push_back(std::move(locked));
  }
  {
    // issue 13: a corrupted cache entry gave a wrong volume with exit 0
    Scene cache =
        runs("corrupted compile cache", "a cached surface with one coordinate byte flipped",
             "rigid body b (material=steel) { difference() { box(0.1); translate([0.05, 0.05, -1]) "
             "cylinder(r=0.02, h=3, segments=32); } }\nsimulate(duration=0.01s, frames=2);\n",
             [](const Outcome& o) {
               if (o.build["bodies"][0]["cached"].get<bool>())
                 return std::string("the entry was used");
               const double hole = 0.5 * 32 * 0.02 * 0.02 * std::sin(2 * M_PI / 32) * 0.1;
               return within("volume (m^3)", o.build["bodies"][0]["volume"].get<double>(),
                             1e-3 - hole, 1e-12);
             });
    cache.prepare = [](const fs::path& dir) -> std::shared_ptr<void> {
      // a first run fills the cache; then one byte of its surface changes
      std::ostringstream quiet;
      run_cli({"run", (dir / "scene.vp").string(), "-o", (dir / "out").string(), "--no-render",
               "--quiet"},
              quiet);
      for (const auto& f : fs::directory_iterator(dir / "out" / ".vproto-cache"))
        if (f.path().extension() == ".mesh") {
          std::fstream bytes(f.path(), std::ios::in | std::ios::out | std::ios::binary);
          bytes.seekg(-64, std::ios::end);
          char c = 0;
          bytes.get(c);
          bytes.seekp(-64, std::ios::end);
          bytes.put(static_cast<char>(c ^ 0x10));
        }
      return nullptr;
    };
    s.push_back(std::move(cache));
  }
  {
    // issue 13: an unreadable import was not named at its place
    Scene garbage =
        refused("unreadable import", "an STL file that is not one",
                "rigid body b (material=steel) {\n  import(\"@DIR@/garbage.stl\");\n}\n",
                "scene.vp:2:3: error: import(): cannot read");
    garbage.prepare = [](const fs::path& dir) -> std::shared_ptr<void> {
      std::ofstream(dir / "garbage.stl") << "solid x\nfacet garbage\n";
      return nullptr;
    };
    s.push_back(std::move(garbage));
  }
  s.push_back(
      refused("factor beyond memory", "a mesh whose factor does not fit",
              "elastic body beam (material=steel, mesh_size=0.02) { box([1, 0.05, 0.05]); }\n"
              "fix beam region=box([-1, -1, -1], [0.001, 1, 1]);\nforce beam [0, 0, -100] "
              "region=box([0.999, -1, -1], [2, 2, 2]);\nsimulate(mode=static);\n",
              "use a mesh_size of at least", "VPROTO_MEMORY_LIMIT=2MB"));
  return s;
}

}  // namespace

int command_stress(const Options& o, std::ostream& err) {
  const auto t0 = Clock::now();
  Progress progress(err, o.quiet);
  const fs::path out(o.out_dir);
  std::error_code ec;
  fs::create_directories(out / "stress", ec);
  if (ec || ::access(out.c_str(), W_OK) != 0)
    throw InputError(SourceLoc{o.out_dir, 0, 0}, "cannot write to the output folder");
  json rows = json::array();
  int failed = 0;
  std::ostringstream table;
  table << "| scene | pushes | expected | got | verdict | seconds |\n|---|---|---|---|---|---|\n";
  for (const Scene& scene : scenes()) {
    if (o.quick && !scene.quick) continue;
    progress.stage("stress: " + scene.name);
    std::string slug;
    for (char c : scene.name) slug += std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
    const fs::path dir = out / "stress" / slug;
    fs::remove_all(dir, ec);
    fs::create_directories(dir, ec);
    const fs::path script = dir / "scene.vp";
    std::string text = scene.script;
    for (std::size_t at = text.find("@DIR@"); at != std::string::npos; at = text.find("@DIR@"))
      text.replace(at, 5, dir.string());
    std::ofstream(script) << text;
    const fs::path run_dir = dir / "out";
    std::shared_ptr<void> stage;
    if (scene.prepare) stage = scene.prepare(dir);
    std::vector<std::string> args = {"run",         script.string(), "-o", run_dir.string(),
                                     "--no-render", "--quiet"};
    args.insert(args.end(), scene.args.begin(), scene.args.end());
    std::string saved;
    const std::string variable = scene.environment.substr(0, scene.environment.find('='));
    if (!scene.environment.empty()) {
      if (const char* v = std::getenv(variable.c_str())) saved = v;
      ::setenv(variable.c_str(), scene.environment.substr(variable.size() + 1).c_str(), 1);
    }
    std::ostringstream messages;
    const auto started = Clock::now();
    const int code = run_cli(args, messages);
    const double seconds = since(started);
    stage.reset();
    if (!scene.environment.empty()) {
      if (saved.empty())
        ::unsetenv(variable.c_str());
      else
        ::setenv(variable.c_str(), saved.c_str(), 1);
    }
    std::string why;
    if (code != scene.exit_code) {
      why = "exit " + std::to_string(code) + ": " + messages.str();
    } else if (code != 0) {
      if (messages.str().find(scene.message) == std::string::npos)
        why = "the message does not say '" + scene.message + "': " + messages.str();
      else if (code == 2 && fs::exists(run_dir / "summary.json"))
        why = "refused, but it wrote outputs";
    } else {
      Outcome outcome;
      try {
        outcome.summary = json::parse(std::ifstream(run_dir / "summary.json"));
        outcome.build = json::parse(std::ifstream(run_dir / "build.json"));
        outcome.history = read_history(run_dir / "history.csv");
      } catch (const std::exception& e) {
        why = std::string("unreadable outputs: ") + e.what();
      }
      bool finite = all_finite(outcome.summary);
      for (const auto& row : outcome.history)
        for (const auto& [k, v] : row) finite = finite && std::isfinite(v);
      if (why.empty() && !finite) why = "a non-finite number in summary.json or history.csv";
      if (why.empty() && outcome.history.empty()) why = "no history";
      if (why.empty() && scene.check) why = scene.check(outcome);
    }
    const bool correct = why.empty();
    failed += !correct;
    const std::string expected = scene.exit_code == 0   ? "correct figure"
                                 : scene.exit_code == 2 ? "refused (exit 2)"
                                                        : "stopped (exit 3)";
    rows.push_back({{"scene", scene.name},
                    {"pushes", scene.pushes},
                    {"expected_exit", scene.exit_code},
                    {"exit", code},
                    {"correct", correct},
                    {"why", why},
                    {"seconds", seconds}});
    std::string first_line = messages.str().substr(0, messages.str().find('\n'));
    table << "| " << scene.name << " | " << scene.pushes << " | " << expected << " | exit " << code
          << (code ? ": " + first_line : std::string()) << " | "
          << (correct ? "correct" : "WRONG: " + why) << " | " << seconds << " |\n";
  }
  const json doc = {
      {"quick", o.quick}, {"scenes", rows}, {"failed", failed}, {"total_seconds", since(t0)}};
  write_text_atomically(out / "stress.json", doc.dump(2) + "\n");
  write_text_atomically(out / "stress.md", table.str());
  progress.stage("stress: " + std::to_string(rows.size() - static_cast<std::size_t>(failed)) +
                 " of " + std::to_string(rows.size()) + " scenes as required -> " + o.out_dir);
  progress.finish();
  return failed ? 3 : 0;
}

}  // namespace vproto::ui_batch::detail
