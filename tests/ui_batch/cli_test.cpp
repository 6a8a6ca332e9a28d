// The vproto executable end to end: exit codes, messages, files (cli.md).
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <sstream>
#include <thread>

#include "png_reader.h"
#include "vproto/sim/linear_solver.h"
#include "vproto/ui_batch/mesh_io.h"

namespace {

namespace fs = std::filesystem;

struct Result {
  int code = -1;
  std::string output;  // stdout and stderr
};

// a shell command line, stdout and stderr together
Result shell(const std::string& command_line) {
  const std::string cmd = command_line + " 2>&1";
  Result r;
  FILE* p = popen(cmd.c_str(), "r");
  std::array<char, 4096> buf;
  while (fgets(buf.data(), buf.size(), p)) r.output += buf.data();
  const int status = pclose(p);
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

Result run(const std::string& args) { return shell(std::string(VPROTO_EXE) + " " + args); }

// a folder of this test process's own, so suites running side by side (two checkouts on
// one machine) do not write into each other's files; removed when the process ends
fs::path scratch() {
  struct Folder {
    fs::path path = fs::temp_directory_path() / ("vproto_cli_" + std::to_string(::getpid()));
    Folder() { fs::create_directories(path); }
    ~Folder() {
      std::error_code ec;
      fs::remove_all(path, ec);
    }
  };
  static const Folder folder;
  return folder.path;
}

fs::path fresh_dir(const std::string& name) {
  const fs::path d = scratch() / ("vproto_cli_" + name);
  fs::remove_all(d);
  return d;
}

// samples/NAME.vp run without rendering into a fresh folder: the command's result and, when
// it succeeded, its summary.json and build.json
struct SampleRun {
  fs::path out;
  Result result;
  nlohmann::json summary, build;
};
SampleRun run_sample(const std::string& name) {
  SampleRun s;
  s.out = fresh_dir(name);
  s.result = run("run " + std::string(VPROTO_SAMPLES) + "/" + name + ".vp -o " + s.out.string() +
                 " --no-render --quiet");
  if (s.result.code == 0) {
    s.summary = nlohmann::json::parse(std::ifstream(s.out / "summary.json"));
    s.build = nlohmann::json::parse(std::ifstream(s.out / "build.json"));
  }
  return s;
}

fs::path write_script(const std::string& name, const std::string& text) {
  const fs::path p = scratch() / name;
  std::ofstream(p) << text;
  return p;
}

TEST(Cli, CheckAndBuildTheSnapFitSample) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/snapfit.vp";
  EXPECT_EQ(run("check " + sample + " --quiet").code, 0);
  const fs::path out = fresh_dir("snapfit");
  const Result r = run("build " + sample + " -o " + out.string());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("csg: socket"), std::string::npos);  // progress on stderr
  const auto doc = nlohmann::json::parse(std::ifstream(out / "build.json"));
  EXPECT_EQ(doc["units"], "SI");
  ASSERT_EQ(doc["bodies"].size(), 2u);
  const auto& socket = doc["bodies"][0];
  EXPECT_EQ(socket["name"], "socket");
  EXPECT_EQ(socket["kind"], "elastic");
  EXPECT_EQ(socket["material"], "ldpe");
  // block + two paws + two hooks, in cubic inches
  const double in3 = std::pow(0.0254, 3);
  EXPECT_NEAR(socket["volume"].get<double>(), (500 + 2 * 0.5 + 2 * 0.5 * 0.1 * 0.1 / 2) * in3,
              1e-12);
  EXPECT_NEAR(socket["mass"].get<double>(), 920 * socket["volume"].get<double>(), 1e-9);
  EXPECT_EQ(socket["convex_parts"], 0);
  EXPECT_TRUE(fs::file_size(out / "socket.stl") > 84);
  EXPECT_TRUE(fs::exists(out / "base_part.stl"));
  EXPECT_TRUE(doc["timings"].contains("csg"));

  // a rebuild with a changed param recomputes the socket only
  const Result r2 = run("build " + sample + " -o " + out.string() + " --set clearance=0.004in");
  ASSERT_EQ(r2.code, 0) << r2.output;
  const auto doc2 = nlohmann::json::parse(std::ifstream(out / "build.json"));
  EXPECT_EQ(doc2["bodies"][0]["cached"], true);
  EXPECT_EQ(doc2["bodies"][1]["cached"], false);
  fs::remove_all(out);
}

TEST(Cli, ObjFormatAndConvexParts) {
  const fs::path script =
      write_script("vproto_cli_l.vp",
                   "rigid body ell (material=steel) {\n"
                   "  difference() { box([2, 2, 1]); translate([1, 1, -1]) box([2, 2, 3]); }\n"
                   "}\n");
  const fs::path out = fresh_dir("obj");
  const Result r =
      run("build " + script.string() + " -o " + out.string() + " --format obj --convex --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << r.output;  // --quiet
  EXPECT_TRUE(fs::exists(out / "ell.obj"));
  const auto doc = nlohmann::json::parse(std::ifstream(out / "build.json"));
  EXPECT_GE(doc["bodies"][0]["convex_parts"].get<int>(), 2);
  EXPECT_NEAR(doc["bodies"][0]["volume"].get<double>(), 3.0, 1e-14);
  fs::remove_all(out);
}

TEST(Cli, BadScriptsExitTwoAndWriteNothing) {
  const fs::path script = write_script(
      "vproto_cli_bad.vp", "rigid body b (material=steel) {\n  box([1, 1lbf, 1]);\n}\n");
  const fs::path out = fresh_dir("bad");
  const Result r = run("build " + script.string() + " -o " + out.string());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find(script.string() + ":2:7: error: box() size component y must be a length"),
            std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(out));
  // geometry errors, found later, leave nothing either
  const fs::path empty =
      write_script("vproto_cli_empty.vp",
                   "rigid body b (material=steel) { intersection() { box(1); "
                   "translate([0.5,0.5,0.5]) box(1); translate([3,0,0]) box(1); } }\n");
  const Result e = run("build " + empty.string() + " -o " + out.string());
  EXPECT_EQ(e.code, 2);
  EXPECT_NE(e.output.find("is empty"), std::string::npos) << e.output;
  EXPECT_FALSE(fs::exists(out));
}

// A feature thinner than the mesh can follow: the snap-fit's hooks with 80-degree lead
// faces are 0.45 mm tall at their root under 6 mm elements, and some of their elements hang
// on the rest by an edge or a corner. The run is refused at the body, naming where and what
// to change (it stopped on a singular K with no body named).
TEST(Cli, AMeshThatDoesNotHoldTogetherIsRefusedAtItsBody) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/snapfit.vp";
  const fs::path out = fresh_dir("loose_mesh");
  const Result r =
      run("run " + sample + " -o " + out.string() + " --no-render --set hook_angle=80deg");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("snapfit.vp:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("body 'socket': the tetrahedral mesh at mesh_size 0.00635 m does not "
                          "hold together"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("give a smaller mesh_size"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

TEST(Cli, CommandLineErrors) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/snapfit.vp";
  EXPECT_EQ(run("").code, 2);
  EXPECT_EQ(run("frobnicate x.vp").code, 2);
  EXPECT_EQ(run("build " + sample).code, 2);  // no -o
  EXPECT_EQ(run("check /nonexistent/x.vp").code, 2);
  EXPECT_EQ(run("check " + sample + " --bogus").code, 2);
  EXPECT_EQ(run("check " + sample + " --set nosuchparam=1").code, 2);
  EXPECT_EQ(run("check " + sample + " --set clearance").code, 2);
  const Result bad_set = run("check " + sample + " --set clearance=3lbf");
  EXPECT_EQ(bad_set.code, 2);
  EXPECT_NE(bad_set.output.find("--set clearance"), std::string::npos) << bad_set.output;
  EXPECT_EQ(run("build " + sample + " -o /tmp/x --format step").code, 2);
  EXPECT_EQ(run("-h").code, 0);
  // an output folder that cannot be made
  const Result ro = run("build " + sample + " -o /proc/vproto_out --quiet");
  EXPECT_EQ(ro.code, 2) << ro.output;
}

}  // namespace

namespace {

TEST(Cli, BuildRendersAPreview) {
  const fs::path out = fresh_dir("preview");
  const Result r = run("build " + std::string(VPROTO_SAMPLES) + "/bracket.vp -o " + out.string() +
                       " --render " + (out / "preview.png").string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  // a PNG of the script's render size (1280 x 720 by default)
  std::ifstream png(out / "preview.png", std::ios::binary);
  unsigned char head[24];
  png.read(reinterpret_cast<char*>(head), 24);
  ASSERT_TRUE(png);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(head) + 1, 3), "PNG");
  const auto be32 = [&](int o) {
    return (head[o] << 24) | (head[o + 1] << 16) | (head[o + 2] << 8) | head[o + 3];
  };
  EXPECT_EQ(be32(16), 1280);
  EXPECT_EQ(be32(20), 720);
  EXPECT_EQ(run("build " + std::string(VPROTO_SAMPLES) + "/bracket.vp -o " + out.string() +
                " --render " + (out / "preview.jpg").string())
                .code,
            2);
  fs::remove_all(out);
}

TEST(Cli, RunOfASceneAtRestWritesFramesMeshesAndReports) {
  const fs::path script =
      write_script("vproto_cli_rest.vp",
                   "rigid body a (material=steel) { box([1, 1, 1]); }\n"
                   "elastic body b (material=abs) { translate([2, 0, 0]) cylinder(h=1, r=0.5); }\n"
                   "fix a;\nprobe p b point=[2, 0, 0.5];\n"
                   "simulate(duration=0.5s, frames=4);\n"
                   "render(size=[320, 200], field=von_mises);\n");
  const fs::path out = fresh_dir("rest");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --export obj --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  for (int k = 0; k < 4; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frame_%04d.png", k);
    EXPECT_TRUE(fs::exists(out / "frames" / name)) << name;
    std::snprintf(name, sizeof name, "b_%04d.obj", k);
    EXPECT_TRUE(fs::exists(out / "meshes" / name)) << name;
  }
  EXPECT_FALSE(fs::exists(out / "frames" / "frame_0004.png"));
  // a body that stays where it was is exported again as the same file (copied, not
  // written anew), and the file reads back whole
  auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  for (const char* body : {"a", "b"}) {
    const std::string first = bytes(out / "meshes" / (std::string(body) + "_0000.obj"));
    EXPECT_FALSE(first.empty()) << body;
    EXPECT_EQ(bytes(out / "meshes" / (std::string(body) + "_0003.obj")), first) << body;
    EXPECT_EQ(
        vproto::ui_batch::read_mesh((out / "meshes" / (std::string(body) + "_0003.obj")).string())
            .F.rows(),
        vproto::ui_batch::read_mesh((out / "meshes" / (std::string(body) + "_0000.obj")).string())
            .F.rows());
  }
  EXPECT_EQ(vproto::ui_batch::read_mesh((out / "meshes" / "a_0002.obj").string()).F.rows(),
            12);  // the box
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["status"], "ok");
  EXPECT_EQ(summary["frames"], 4);
  EXPECT_DOUBLE_EQ(summary["sim_time"].get<double>(), 0.5);
  EXPECT_EQ(summary["probes"]["p"]["u"], nlohmann::json::array({0.0, 0.0, 0.0}));
  std::ifstream history(out / "history.csv");
  std::string header, line;
  std::getline(history, header);
  EXPECT_EQ(header.rfind("t,step,contacts,contact_force,kinetic_energy,strain_energy,external_work,"
                         "max_von_mises,a_x,a_y,a_z,b_x",
                         0),
            0u)
      << header;
  EXPECT_NE(header.find("p_ux,p_uy,p_uz"), std::string::npos);
  int rows = 0;
  while (std::getline(history, line)) ++rows;
  EXPECT_EQ(rows, summary["steps"].get<int>() + 1);  // the start, then one row per step
  EXPECT_TRUE(fs::exists(out / "build.json"));
  // --no-render writes no frames
  const fs::path out2 = fresh_dir("rest2");
  ASSERT_EQ(
      run("run " + script.string() + " -o " + out2.string() + " --no-render --export none --quiet")
          .code,
      0);
  EXPECT_FALSE(fs::exists(out2 / "frames"));
  EXPECT_TRUE(fs::exists(out2 / "summary.json"));
  fs::remove_all(out);
  fs::remove_all(out2);
}

std::vector<std::map<std::string, double>> read_history(const fs::path& file);
// The history's row nearest time t.
const std::map<std::string, double>& row_at(const std::vector<std::map<std::string, double>>& rows,
                                            double t);

// A steel puck dropped 0.15 m onto an ABS pad clamped by its bottom face: contact moves
// the free puck (its mobility in the rows), it lands once at sqrt(2 h / g) and rests on
// the pad, whose clamp then carries both weights.
TEST(Cli, RunDropsAFreeRigidPuckOnAClampedElasticPad) {
  const fs::path out = fresh_dir("puck");
  const fs::path script = write_script(
      "vproto_cli_free_partner.vp",
      "elastic body pad (material=abs, mesh_size=0.02) { box([0.1, 0.1, 0.05]); }\n"
      "rigid body puck (material=steel) { translate([0, 0, 0.2]) box([0.05, 0.05, 0.05]); }\n"
      "fix pad region=box([-1, -1, -1], [1, 1, 0.001]);\ngravity [0, 0, -9.81];\n"
      "simulate(duration=0.4s, frames=5);\n");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto build = nlohmann::json::parse(std::ifstream(out / "build.json"));
  ASSERT_EQ(summary["events"].size(), 1u) << summary["events"].dump();
  EXPECT_EQ(summary["events"][0]["type"], "contact_added");
  EXPECT_NEAR(summary["events"][0]["t"].get<double>(), std::sqrt(2 * 0.15 / 9.81),
              summary["time_step"].get<double>());
  EXPECT_NE(summary["note"].get<std::string>().find("pad deforms quasi-statically"),
            std::string::npos);
  const double pad = build["bodies"][0]["mass"], puck = build["bodies"][1]["mass"];
  const auto rows = read_history(out / "history.csv");
  ASSERT_FALSE(rows.empty());
  EXPECT_NEAR(rows.back().at("pad_rz"), (pad + puck) * 9.81, 1e-4 * (pad + puck) * 9.81);
  EXPECT_NEAR(rows.back().at("contact_force"), puck * 9.81, 1e-4 * puck * 9.81);
  EXPECT_NEAR(rows.back().at("puck_z"), 0.075, 1e-5);  // on the pad, not in it
  // and at rest there: every contact solve converged, and the puck does not creep (the
  // sweeps alone, before the Newton finish, left it creeping by 1e-7 m per 0.1 s)
  EXPECT_EQ(summary["elastic_contact"]["unconverged_solves"], 0);
  EXPECT_GT(summary["elastic_contact"]["newton_iterations"].get<long>(), 0);
  // columns and Delassus blocks on the second core where there is one (no mpirun here)
  EXPECT_EQ(summary["elastic_contact"]["threads"],
            std::thread::hardware_concurrency() >= 2 ? 2 : 1);
  const auto& mid = rows[rows.size() * 3 / 4];
  ASSERT_GT(mid.at("t"), 0.25);  // landed at 0.175 s
  for (const char* axis : {"puck_x", "puck_y", "puck_z"})
    EXPECT_NEAR(rows.back().at(axis), mid.at(axis), 1e-12) << axis;

  // contact_steps.csv: the pad's stage, step by step, adds up to the summary's figures
  const auto& ec = summary["elastic_contact"];
  const auto steps = read_history(out / "contact_steps.csv");
  ASSERT_EQ(static_cast<long>(steps.size()), ec["steps_with_rows"].get<long>());
  {
    std::ifstream in(out / "contact_steps.csv");
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) EXPECT_EQ(line.substr(line.find(',') + 1, 4), "pad,") << line;
  }
  long newton = 0, columns = 0;
  double seconds = 0, slowest = 0, slowest_t = -1;
  int most = 0;
  for (const auto& st : steps) {
    EXPECT_GE(st.at("detected"), 1);
    EXPECT_GE(st.at("points"), st.at("pressed"));
    EXPECT_GE(st.at("points"), st.at("node_points"));
    EXPECT_GE(st.at("pressed"), st.at("sliding"));
    EXPECT_GE(st.at("passes"), 1);
    EXPECT_EQ(st.at("converged"), 1);
    EXPECT_LE(st.at("column_seconds") + st.at("delassus_seconds") + st.at("solve_seconds"),
              st.at("seconds") * (1 + 1e-9));
    newton += static_cast<long>(st.at("newton_iterations"));
    columns += static_cast<long>(st.at("new_columns"));
    seconds += st.at("seconds");
    most = std::max(most, static_cast<int>(st.at("points")));
    if (st.at("seconds") > slowest) {
      slowest = st.at("seconds");
      slowest_t = st.at("t");
    }
  }
  EXPECT_GT(steps.back().at("pressed"), 0);  // the puck rests on the pad to the end
  EXPECT_EQ(newton, ec["newton_iterations"].get<long>());
  EXPECT_EQ(columns, ec["response_solves"].get<long>());  // the pad is clamped: no frame modes
  EXPECT_EQ(most, ec["max_points"].get<int>());
  EXPECT_LE(seconds, ec["seconds"].get<double>() * (1 + 1e-9));
  EXPECT_EQ(ec["steps_file"], "contact_steps.csv");
  EXPECT_NEAR(ec["slowest_step"]["t"].get<double>(), slowest_t, 1e-6 * slowest_t);
  EXPECT_EQ(ec["slowest_step"]["body"], "pad");
  fs::remove_all(out);
}

// Two elastic blocks pressed together (quasi-static, frictionless, nu = 0): a column of
// two springs in series, F = E A d / (L_top + L_bottom) = 10 MPa * 400 mm^2 * 0.05 mm /
// 50 mm = 4 N, which the FE meshes represent exactly (uniform strain). The contact points go
// both ways (each block's nodes on the other's triangles) over non-matching meshes (4 and 3
// mm): node-to-surface contact leaves the interface a little soft there (0.3 % here, 0.17 %
// at 2 / 1.5 mm; 0.07 % when both are meshed at 4 mm), and nothing passes through.
TEST(Cli, RunPressesTwoElasticBlocksTogether) {
  const fs::path out = fresh_dir("elastic_pair");
  const fs::path script =
      write_script("vproto_cli_elastic_pair.vp",
                   "units length=mm force=N;\n"
                   "material soft { E = 10MPa; nu = 0; density = 1000kg/m^3; friction = 0; }\n"
                   "elastic body top (material=soft, mesh_size=4mm, element=tet10) {\n"
                   "  translate([-10mm, -10mm, 0]) box([20mm, 20mm, 20mm]); }\n"
                   "elastic body bottom (material=soft, mesh_size=3mm, element=tet10) {\n"
                   "  translate([-10mm, -10mm, -30mm]) box([20mm, 20mm, 30mm]); }\n"
                   "fix bottom region=box([-11mm, -11mm, -31mm], [11mm, 11mm, -29.9mm]);\n"
                   "grip top region=box([-11mm, -11mm, 19.9mm], [11mm, 11mm, 21mm]);\n"
                   "move top by=[0, 0, -0.05mm] over=1s;\n"
                   "contact top bottom friction=0;\n"
                   "simulate(mode=quasistatic, duration=1s, frames=5);\nexport(format=none);\n");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto rows = read_history(out / "history.csv");
  ASSERT_EQ(rows.size(), 5u);
  for (std::size_t k = 1; k < rows.size(); ++k) {
    const double expected = 4.0 * rows[k].at("t");  // the press is linear in time
    // the grip pushes down, the clamp up, by the same force: the contact's
    EXPECT_NEAR(-rows[k].at("top_rz"), expected, 5e-3 * expected) << rows[k].at("t");
    EXPECT_LT(-rows[k].at("top_rz"), expected) << "node-to-surface is softer, never stiffer";
    EXPECT_NEAR(rows[k].at("bottom_rz"), -rows[k].at("top_rz"), 1e-9);
    EXPECT_NEAR(rows[k].at("contact_force"), -rows[k].at("top_rz"), 1e-9);
    EXPECT_GT(rows[k].at("contacts"), 100);
  }
  EXPECT_EQ(summary["elastic_contact"]["unconverged_solves"], 0);
  EXPECT_LT(summary["elastic_contact"]["max_penetration"].get<double>(), 1e-9);  // of 50 um
  EXPECT_EQ(summary["events"][0]["type"], "contact_added");
  fs::remove_all(out);
}

// samples/elastic_stack.vp: two free rubber blocks dropped onto a slab, the small one onto
// the big one. The big one lands first (1 mm: 14 ms), the small one on it (5 mm: 32 ms),
// and they end stacked on the slab, nothing sunk in.
TEST(Cli, TheElasticStackSampleStacksTwoFreeElasticBlocks) {
  const SampleRun ran = run_sample("elastic_stack");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const fs::path& out = ran.out;
  const auto& s = ran.summary;
  const auto& events = s["events"];
  ASSERT_GE(events.size(), 2u) << s.dump(2);
  EXPECT_EQ(events[0]["bodies"], nlohmann::json::array({"lower", "slab"}));
  EXPECT_NEAR(events[0]["t"].get<double>(), std::sqrt(2 * 0.001 / 9.81), 2e-3);
  EXPECT_EQ(events[1]["bodies"], nlohmann::json::array({"lower", "upper"}));
  EXPECT_NEAR(events[1]["t"].get<double>(), std::sqrt(2 * 0.005 / 9.81), 2e-3);
  EXPECT_EQ(events.back()["type"], "contact_added");                      // they end touching
  EXPECT_NEAR(s["bodies"][1]["position"][2].get<double>(), 0.010, 1e-5);  // lower on the slab
  EXPECT_NEAR(s["bodies"][2]["position"][2].get<double>(), 0.030, 1e-5);  // upper on lower
  EXPECT_LT(s["elastic_contact"]["max_penetration"].get<double>(), 1e-6);
  EXPECT_GE(s["energy"]["dissipated"].get<double>(), 0);
  // both come to rest (the upper block, whose only contact the lower one's stage solves,
  // with it) and do no FE work for at least the run's second half: half its steps each
  EXPECT_GE(s["elastic_contact"]["resting_steps"].get<int>(), s["steps"].get<int>())
      << s["elastic_contact"];
  fs::remove_all(out);
}

// samples/bumper_carriage.vp: a rubber bumper gripped to a carriage on a slider (its frame
// a body of the carriage's mechanism), pushed by 2 N into a free steel block. The bumper
// reaches the block when the pushed pair has covered the 5 mm gap, (m_c + m_r) 2 * 5 mm /
// 2 N = 18.9 ms; the bumper stays on the carriage (the joint holds to rounding); and the
// push is the only load along x, so the three bodies' centre of mass moves by F t^2 / 2
// over their mass whatever the contact did (to 1e-9).
TEST(Cli, TheBumperCarriageSampleShovesTheBlockAlong) {
  const SampleRun ran = run_sample("bumper_carriage");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const fs::path& out = ran.out;
  const auto& s = ran.summary;
  const auto& b = ran.build;
  const auto& events = s["events"];
  ASSERT_GE(events.size(), 1u) << s.dump(2);
  EXPECT_EQ(events[0]["bodies"], nlohmann::json::array({"bumper", "block"}));
  double mass[3], moved = 0;
  const double start[3] = {-0.03, -0.01, 0.015};  // centroids' x at the start
  for (int k = 0; k < 3; ++k) mass[k] = b["bodies"][k]["mass"].get<double>();
  EXPECT_NEAR(events[0]["t"].get<double>(), std::sqrt(2 * 0.005 * (mass[0] + mass[1]) / 2), 1e-3);
  EXPECT_LT(s["max_joint_drift"].get<double>(), 1e-12);
  const auto& bodies = s["bodies"];
  EXPECT_NEAR(bodies[1]["position"][0].get<double>() - bodies[0]["position"][0].get<double>(), 0.02,
              1e-12);
  for (int k = 0; k < 3; ++k)
    moved += mass[k] * (bodies[k]["position"][0].get<double>() - start[k]);
  EXPECT_NEAR(moved, 0.5 * 2 * 0.1 * 0.1, 1e-9 * 0.01);
  EXPECT_GT(bodies[2]["position"][0].get<double>() - start[2], 0.05);  // shoved along
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(out);
}

// samples/rubber_blocks_pushed.vp: two rubber blocks on a steel table (friction 0.5), one
// pushed by a steady 0.15 N into the other 1 mm ahead: both press on the table while they
// touch (their pair's rows and the pushed one's on the table are one problem). The pusher
// reaches it after sqrt(2 mm / ((F - mu m g) / m)) = 12.9 ms, and from then on they slide
// together at (F - 2 mu m g) / 2m, to 1e-4 from the history's positions at 50, 100 and
// 150 ms.
TEST(Cli, TheRubberBlocksPushedSampleSlideTogether) {
  const SampleRun ran = run_sample("rubber_blocks_pushed");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const fs::path& out = ran.out;
  const auto& s = ran.summary;
  const auto& b = ran.build;
  const double m = b["bodies"][1]["mass"].get<double>(), g = 9.81, mu = 0.5, f = 0.15;
  EXPECT_NEAR(b["bodies"][2]["mass"].get<double>(), m, 1e-12);
  std::optional<double> met;
  for (const auto& e : s["events"])
    if (e["bodies"] == nlohmann::json::array({"pusher", "pushed"}) && !met)
      met = e["t"].get<double>();
  ASSERT_TRUE(met) << s["events"];
  EXPECT_NEAR(*met, std::sqrt(2 * 0.001 / ((f - mu * m * g) / m)), 5e-4);
  const auto rows = read_history(out / "history.csv");
  const auto &x0 = row_at(rows, 0.05), &x1 = row_at(rows, 0.10), &x2 = row_at(rows, 0.15);
  const double h = x1.at("t") - x0.at("t"), expected = (f - 2 * mu * m * g) / (2 * m);
  for (const std::string body : {"pusher", "pushed"}) {
    const std::string x = body + "_x";
    EXPECT_NEAR((x2.at(x) - 2 * x1.at(x) + x0.at(x)) / (h * h), expected, 1e-4 * expected) << body;
  }
  EXPECT_NEAR(x2.at("pushed_x") - x2.at("pusher_x"), x0.at("pushed_x") - x0.at("pusher_x"), 1e-6);
  // the kinetic energy is that of the speed the positions move at (central differences of
  // the history's positions): their frames, both held by the table, end their steps so
  // (Dynamics::held_shifts; it was 0.9 % high at 0.1 s, half a step's friction too fast)
  for (const double t : {0.10, 0.14}) {
    const auto& at = row_at(rows, t);
    const std::size_t k = static_cast<std::size_t>(&at - rows.data());
    ASSERT_TRUE(k > 0 && k + 1 < rows.size());
    const auto &before = rows[k - 1], &after = rows[k + 1];
    double moving = 0;
    for (const std::string body : {"pusher", "pushed"}) {
      const double speed =
          (after.at(body + "_x") - before.at(body + "_x")) / (after.at("t") - before.at("t"));
      moving += 0.5 * m * speed * speed;
    }
    EXPECT_NEAR(at.at("kinetic_energy"), moving, 1e-6 * moving) << t;
  }
  EXPECT_LT(s["elastic_contact"]["max_penetration"].get<double>(), 1e-6);
  // the blocks' pair and the pushed block's rows on the table: one problem, no passes
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0);
  EXPECT_EQ(s["elastic_contact"]["shared_passes"].get<long>(), 0);
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(out);
}

// Two rubber blocks (those of samples/rubber_blocks_pushed.vp) side by side on `under`,
// touching, the first pushed against the other with 0.06 N (ramped over 50 ms), below what
// their friction holds (2 mu m g = 0.086 N), run with `frames` frames over 0.4 s (the step
// divides the frame interval): they stay put (to 1e-9 m from 0.2 s to 0.4 s, and within
// 1 um of where they started), fall asleep (kinetic energy below 1e-15 J) and the pusher's
// contacts answer the push (to 1e-5), their rows solved as one problem with no passes.
// `mat` names a floating body under them that must stay put as well.
void expect_blocks_pressed_together_stay_put(const std::string& name, const std::string& under,
                                             const std::string& mat, int frames) {
  const fs::path out = fresh_dir(name);
  const fs::path script = write_script(
      "vproto_cli_" + name + ".vp",
      "units length=mm;\n"
      "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; friction = 0.5; }\n" +
          under +
          "elastic body pusher (material=rubber, mesh_size=10mm, element=tet4) {\n"
          "  translate([-20, -10, 0]) box([20, 20, 20]); }\n"
          "elastic body pushed (material=rubber, mesh_size=10mm, element=tet4) {\n"
          "  translate([0, -10, 0]) box([20, 20, 20]); }\n"
          "fix table;\ngravity [0, 0, -9.81m/s^2];\n"
          "force pusher [0.06N, 0, 0] ramp=0.05s;\n"
          "simulate(mode=dynamic, duration=0.4s, frames=" +
          std::to_string(frames) + ");\nexport(format=none);\n");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto b = nlohmann::json::parse(std::ifstream(out / "build.json"));
  const std::string which = name + " " + std::to_string(frames);
  const double m = b["bodies"][mat.empty() ? 1 : 2]["mass"].get<double>(), push = 0.06;
  ASSERT_LT(push, 2 * 0.5 * m * 9.81);  // (held by their friction)
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0) << which;
  EXPECT_EQ(s["elastic_contact"]["shared_passes"].get<long>(), 0) << which;
  EXPECT_GT(s["elastic_contact"]["resting_steps"].get<long>(), 0) << which;
  const auto rows = read_history(out / "history.csv");
  const auto &x0 = row_at(rows, 0.2), &x1 = row_at(rows, 0.4);
  std::vector<std::string> bodies{"pusher", "pushed"};
  if (!mat.empty()) bodies.push_back(mat);
  for (const std::string& body : bodies)
    for (const std::string axis : {"_x", "_y", "_z"}) {
      EXPECT_NEAR(x1.at(body + axis), x0.at(body + axis), 1e-9) << which << body << axis;
      EXPECT_NEAR(x1.at(body + axis), rows.front().at(body + axis), 1e-6) << which << body << axis;
    }
  EXPECT_NEAR(x1.at("pusher_cx"), -push, 1e-5 * push) << which;
  EXPECT_LT(x1.at("kinetic_energy"), 1e-15) << which;
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(out);
}

// On the steel table: their pair's rows and the pushed block's on the table are one problem.
// (Stage by stage, the pusher's holding the other on its supports, they crept 8.5 um in
// 0.2 s, never slept and answered the push 0.7 % short.)
TEST(Cli, TwoRubberBlocksPressedTogetherOnATableBelowTheirFrictionStayPut) {
  expect_blocks_pressed_together_stay_put(
      "blocks_pressed",
      "rigid body table (material=steel) { translate([-60, -40, -10]) box([160, 80, 10]); }\n"
      "contact table pusher friction=0.5;\ncontact table pushed friction=0.5;\n",
      "", 41);
}

// On a loose rubber mat on the table (samples/rubber_blocks_pushed_on_loose_mat.vp's), whose
// stage solves both blocks' rows on it while the pusher's solves their pair: the three
// solved as one. (Stage by stage, at 1.9 ms steps, they crept 28 um and took 24 s; solved as
// one with each stage's first guess of where the pushed block goes leaving out the others'
// forces on it, at 2 ms steps its rows on the mat came and went from step to step and they
// never slept.)
TEST(Cli, TwoRubberBlocksPressedTogetherOnALooseMatBelowTheirFrictionStayPut) {
  for (const int frames : {36, 41})
    expect_blocks_pressed_together_stay_put(
        "blocks_pressed_on_mat",
        "rigid body table (material=steel) { translate([-60, -40, -20]) box([160, 80, 10]); }\n"
        "elastic body mat (material=rubber, mesh_size=10mm, element=tet4) {\n"
        "  translate([-40, -20, -10]) box([120, 40, 10]); }\n"
        "contact table mat friction=0.3;\n",
        "mat", frames);
}

// A rubber cube dropped 0.5 mm onto another on a loose rubber mat on the table, the top one
// pushed with 0.03 N (ramped over 0.1 s; the friction between the cubes holds 0.043 N): the
// mat's stage solves the lower cube's rows on it, the lower cube's their pair, as one
// problem. After the landing the cubes stay put (to 1e-9 m from 0.15 s to 0.3 s, the
// upper one within 2 um of where the push found it, its shear under the push) and sleep.
// (Stage by stage, the two crept on together at 44 um/s, never asleep.)
TEST(Cli, TwoRubberCubesStackedOnALooseMatTheTopOnePushedBelowItsFrictionStayPut) {
  const fs::path out = fresh_dir("cubes_stacked_on_mat");
  const fs::path script = write_script(
      "vproto_cli_cubes_stacked_on_mat.vp",
      "units length=mm;\n"
      "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; friction = 0.5; }\n"
      "rigid body table (material=steel) { translate([-60, -40, -20]) box([160, 80, 10]); }\n"
      "elastic body mat (material=rubber, mesh_size=10mm, element=tet4) {\n"
      "  translate([-40, -20, -10]) box([120, 40, 10]); }\n"
      "elastic body lower (material=rubber, mesh_size=10mm, element=tet4) {\n"
      "  translate([-10, -10, 0.5]) box([20, 20, 20]); }\n"
      "elastic body upper (material=rubber, mesh_size=10mm, element=tet4) {\n"
      "  translate([-10, -10, 21]) box([20, 20, 20]); }\n"
      "fix table;\ngravity [0, 0, -9.81m/s^2];\ncontact table mat friction=0.3;\n"
      "force upper [0.03N, 0, 0] ramp=0.1s;\n"
      "simulate(mode=dynamic, duration=0.3s, frames=31);\nexport(format=none);\n");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0);
  EXPECT_EQ(s["elastic_contact"]["shared_passes"].get<long>(), 0);
  EXPECT_GT(s["elastic_contact"]["resting_steps"].get<long>(), 0);
  const auto rows = read_history(out / "history.csv");
  const auto &x0 = row_at(rows, 0.15), &x1 = row_at(rows, 0.3), &landed = row_at(rows, 0.02);
  for (const std::string body : {"mat", "lower", "upper"})
    for (const std::string axis : {"_x", "_y", "_z"})
      EXPECT_NEAR(x1.at(body + axis), x0.at(body + axis), 1e-9) << body << axis;
  EXPECT_NEAR(x1.at("upper_x"), landed.at("upper_x"), 2e-6);
  EXPECT_NEAR(x1.at("lower_z"), 0.01, 1e-6);  // (on the mat: its top at z = 0)
  EXPECT_LT(x1.at("kinetic_energy"), 1e-15);
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(out);
}

// The paw of samples/paw_quasistatic.vp with 85-degree hook faces: its hook is a fin 0.12 mm
// thin under elements of 2.54 mm (mesh_size 0.1 in). `vproto build --tets` warns, naming
// the body's line, the wall and a mesh_size that follows it, and build.json gives the wall;
// the sample as written (45 degrees) builds without a warning. Run, the fin lets the catch
// through: exit 3, the message giving the finer mesh as a fix besides a smaller dt (alone,
// "use a smaller dt" did not help: at a quarter of it the fin failed the same way).
TEST(Cli, AHookTooThinForItsMeshIsWarnedOfAndNamedWhereItFails) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path out = fresh_dir("thin_hook");
  const Result built =
      run("build " + sample + " -o " + out.string() + " --tets --set hook_angle=85deg");
  ASSERT_EQ(built.code, 0) << built.output;
  EXPECT_NE(built.output.find("paw_quasistatic.vp:23:1: warning: body 'paw': its thinnest wall, "
                              "0.00012 m thick"),
            std::string::npos)
      << built.output;
  EXPECT_NE(built.output.find("give a mesh_size of 0.00012 m or less"), std::string::npos);
  const auto b = nlohmann::json::parse(std::ifstream(out / "build.json"));
  ASSERT_EQ(b["warnings"].size(), 1u);  // (kept there too, for quiet runs: a sweep's)
  EXPECT_NE(b["warnings"][0].get<std::string>().find("warning: body 'paw': its thinnest wall"),
            std::string::npos);
  const double wall = b["bodies"][0]["tet_mesh"]["thinnest_wall"].get<double>();
  // the fin under faces at 85 degrees: 0.08 in deep, 2 x 0.08 in / tan(85 deg) at its root
  EXPECT_GT(wall, 0);
  EXPECT_LT(wall, 2 * 0.08 * 0.0254 / std::tan(85 * M_PI / 180));
  const fs::path plain = fresh_dir("thick_hook");
  const Result as_written = run("build " + sample + " -o " + plain.string() + " --tets");
  ASSERT_EQ(as_written.code, 0) << as_written.output;
  EXPECT_EQ(as_written.output.find("warning"), std::string::npos) << as_written.output;
  EXPECT_TRUE(nlohmann::json::parse(std::ifstream(plain / "build.json"))["warnings"].empty());
  // (without friction: with it, on the canonically ordered CSG's mesh, the paw rode over the
  // coarse elements' version of the fin at 15.5 N, no overlap deeper than 6 um, and slid on
  // down the catch's face at 2.66 N: README "Not yet")
  const Result ran = run("run " + sample + " -o " + out.string() +
                         " --no-render --set hook_angle=85deg --set mu=0 --duration 0.7");
  EXPECT_EQ(ran.code, 3) << ran.output;
  EXPECT_NE(ran.output.find("contact between 'paw' and 'catch' could not be resolved"),
            std::string::npos)
      << ran.output;
  EXPECT_NE(ran.output.find("or a finer mesh_size for 'paw' (now 0.00254 m, 21 times its thinnest "
                            "wall, 0.00012 m"),
            std::string::npos)
      << ran.output;
  fs::remove_all(out);
  fs::remove_all(plain);
}

// samples/rubber_blocks_on_tray.vp: the same blocks on a free ABS tray (40 g) that lies on
// the steel table (friction 0.1): both blocks press on the tray, which moves, while they
// touch (the pusher's stage holds the other on its supports on the tray, the tray's
// mobility joining the rows). They slide together on it at (F - 2 mu m g) / 2m, and drag it
// at (2 mu m g - mu_t (M + 2m) g) / M, to 1e-4 from the history's positions at 50, 100 and
// 150 ms (1e-7 found). (The run was stopped when the blocks met, and the tray's friction on
// the table carried only its own weight: 1.18 m/s^2.)
TEST(Cli, TheRubberBlocksOnATraySampleDragTheTray) {
  const SampleRun ran = run_sample("rubber_blocks_on_tray");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const fs::path& out = ran.out;
  const auto& s = ran.summary;
  const auto& b = ran.build;
  ASSERT_EQ(b["bodies"][1]["name"], "tray");
  const double big_m = b["bodies"][1]["mass"].get<double>(),
               m = b["bodies"][2]["mass"].get<double>(), g = 9.81, mu = 0.5, table_mu = 0.1,
               f = 0.15;
  bool met = false;
  for (const auto& e : s["events"])
    met = met || e["bodies"] == nlohmann::json::array({"pusher", "pushed"});
  EXPECT_TRUE(met) << s["events"];
  const auto rows = read_history(out / "history.csv");
  const auto &x0 = row_at(rows, 0.05), &x1 = row_at(rows, 0.10), &x2 = row_at(rows, 0.15);
  const double h = x1.at("t") - x0.at("t");
  auto acceleration = [&](const std::string& body) {
    const std::string x = body + "_x";
    return (x2.at(x) - 2 * x1.at(x) + x0.at(x)) / (h * h);
  };
  const double blocks = (f - 2 * mu * m * g) / (2 * m),
               tray = (2 * mu * m * g - table_mu * (big_m + 2 * m) * g) / big_m;
  for (const std::string body : {"pusher", "pushed"})
    EXPECT_NEAR(acceleration(body), blocks, 1e-4 * blocks) << body;
  EXPECT_NEAR(acceleration("tray"), tray, 1e-4 * tray);
  EXPECT_NEAR(x2.at("pushed_x") - x2.at("pusher_x"), x0.at("pushed_x") - x0.at("pusher_x"), 1e-6);
  // nothing sinks: the deepest is the first step's settling from rest, g dt^2 / 2 (1.5 um
  // at the run's 0.56 ms)
  const double dt = s["time_step"].get<double>();
  EXPECT_LT(s["elastic_contact"]["max_penetration"].get<double>(), 0.51 * g * dt * dt);
  // the blocks' rows, their pair and theirs on the tray, as one problem
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0);
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(out);
}

// samples/block_on_beam_on_rubber_feet.vp: a steel beam on two rubber feet, a steel block on
// it pushed with a force that grows from 0 to 0.15 N over 0.12 s. Held by its friction
// (0.3) until the push reaches mu m g, the block moves with the beam and the feet carry the
// push between them; from then on it slides at (F - mu m g) / m, the feet carrying mu m g
// and holding the beam. (The first foot's stage solves the block's contact with the beam,
// and the two feet's stages agree on their forces on it, Dynamics::coupled_stages.)
// A steel beam (100 x 20 x 10 mm) resting on two rubber pads (20 mm square, 10 mm tall,
// clamped at their feet, friction 0.5), pushed along with 0.3 N that grows over 50 ms, which
// the pads' friction holds: the beam moves only as far as the pads shear, the same for both
// (it is rigid), and the pads, alike, carry half the push each. The pads' rows are solved
// as one problem (Dynamics::stage_group): 50.2 and 49.8 % found. Solved one pad after the
// other, each stage taking the other's forces as loads to come, and passed again until
// those agreed, the pads carried 42 and 58 %.
TEST(Cli, TwoRubberPadsUnderABeamShareAPushTheirFrictionHolds) {
  const fs::path script = write_script("vproto_cli_pads_share.vp", R"(units length=mm;
material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; }
elastic body left (material=rubber, mesh_size=5mm, element=tet4) {
  translate([-50, -10, -10]) box([20, 20, 10]);
}
elastic body right (material=rubber, mesh_size=5mm, element=tet4) {
  translate([30, -10, -10]) box([20, 20, 10]);
}
rigid body beam (material=steel) { translate([-50, -10, 0]) box([100, 20, 10]); }
fix left region=box([-60, -20, -10.1], [-20, 20, -9.9]);
fix right region=box([20, -20, -10.1], [60, 20, -9.9]);
gravity [0, 0, -9.81m/s^2];
contact left beam friction=0.5;
contact right beam friction=0.5;
nocontact left right;
force beam [0.3N, 0, 0] ramp=0.05s;
simulate(mode=dynamic, duration=0.1s, frames=2, dt=1.5ms);
)");
  const fs::path out = fresh_dir("pads_share");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto rows = read_history(out / "history.csv");
  const auto& last = rows.back();
  EXPECT_NEAR(last.at("left_rx") + last.at("right_rx"), -0.3, 1e-6);
  for (const char* pad : {"left_rx", "right_rx"}) EXPECT_NEAR(last.at(pad), -0.15, 0.006) << pad;
  // held: the beam moved by the pads' shear only (micrometres)
  EXPECT_LT(std::abs(last.at("beam_x")), 5e-6);
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0);
  EXPECT_EQ(s["elastic_contact"]["shared_passes"], 0);
  fs::remove_all(out);
}

// samples/rubber_jaws_lift_a_block.vp: two rubber jaws close on a steel block on a table,
// squeeze it and lift it 10 mm. The block rises with them (10 mm, and the squeezed rubber's
// bulge: 10.17 mm found), held by their friction alone: the jaws' vertical reactions carry
// the block's weight and their own. Their rows are one problem at every step, so what each
// jaw carries is the same whichever the script lists first (0.25 % of the weight apart
// found; stage by stage with passes 5 %).
TEST(Cli, TheRubberJawsSampleLiftsTheBlockTheSameWhicheverJawComesFirst) {
  const SampleRun ran = run_sample("rubber_jaws_lift_a_block");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const auto rows = read_history(ran.out / "history.csv");
  const auto& last = rows.back();
  const double rise = last.at("block_z") - rows.front().at("block_z");
  EXPECT_GT(rise, 0.0099);
  EXPECT_LT(rise, 0.0103);
  double weights = 0;
  for (const auto& body : ran.build["bodies"])
    if (body["name"] != "table") weights += body["mass"].get<double>() * 9.81;
  const double carried = last.at("left_jaw_rz") + last.at("right_jaw_rz");
  EXPECT_NEAR(carried, weights, 1e-6 * weights);
  EXPECT_GT(ran.summary["elastic_contact"]["joint_solves"].get<long>(), 0);
  // the block goes up at the jaws' 0.1 m/s while they lift it (the rubber's bulge adds 1e-4),
  // and is still when they stop: its steps end at the velocity the jaws hold it at (ended at
  // g dt / 2 less, 12 % of the kinetic energy short, and 1.2 uJ at rest, before)
  ASSERT_EQ(ran.build["bodies"][1]["name"], "block");
  const double lifted = 0.5 * ran.build["bodies"][1]["mass"].get<double>() * 0.1 * 0.1;
  for (const auto& row : rows)
    if (row.at("t") >= 0.04 && row.at("t") <= 0.11) {
      EXPECT_NEAR(row.at("kinetic_energy"), lifted, 1e-3 * lifted) << row.at("t");
    }
  EXPECT_LT(last.at("kinetic_energy"), 1e-15);
  // the same script with the jaws listed the other way round
  std::string text;
  {
    std::stringstream in;
    in << std::ifstream(std::string(VPROTO_SAMPLES) + "/rubber_jaws_lift_a_block.vp").rdbuf();
    text = in.str();
  }
  const std::size_t a = text.find("elastic body left_jaw"), b = text.find("elastic body right_jaw"),
                    c = text.find("\nfix table");
  ASSERT_TRUE(a != std::string::npos && b > a && c > b);
  const std::string swapped =
      text.substr(0, a) + text.substr(b, c - b) + text.substr(a, b - a) + text.substr(c);
  const fs::path script = write_script("vproto_cli_jaws_swapped.vp", swapped);
  const fs::path out = fresh_dir("jaws_swapped");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto& other = read_history(out / "history.csv").back();
  const double block = weights - 2 * 9.81 * ran.build["bodies"][2]["mass"].get<double>();
  for (const char* jaw : {"left_jaw_rz", "right_jaw_rz"})
    EXPECT_NEAR(other.at(jaw), last.at(jaw), 0.01 * block) << jaw;
  fs::remove_all(out);
  fs::remove_all(ran.out);
}

TEST(Cli, TheBlockOnABeamOnRubberFeetSampleHoldsThenSlides) {
  const SampleRun ran = run_sample("block_on_beam_on_rubber_feet");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const auto& s = ran.summary;
  ASSERT_EQ(ran.build["bodies"][3]["name"], "block");
  const double m = ran.build["bodies"][3]["mass"].get<double>(), g = 9.81, mu = 0.3;
  const double rate = 0.15 / 0.12, slip = mu * m * g / rate;  // N/s; when the push reaches mu m g
  const double dt = s["time_step"].get<double>();
  const auto rows = read_history(ran.out / "history.csv");
  double first = -1;  // when the block has slid 0.1 um over the beam
  for (const auto& row : rows) {
    const double t = row.at("t");
    const double feet = row.at("left_foot_rx") + row.at("right_foot_rx");
    if (first < 0 && std::abs(row.at("block_x") - row.at("beam_x")) > 1e-7) first = t;
    if (t > 0.02 && t < slip - 2 * dt) {
      // held: the feet carry the push, one step behind it (2e-4 of a step's growth found),
      // and the block goes with the beam (their centres part by the beam's pitch: 9 nm)
      EXPECT_NEAR(feet, -rate * (t - dt), 1e-3 * rate * dt) << t;
      EXPECT_LT(std::abs(row.at("block_x") - row.at("beam_x")), 2e-8) << t;
    }
    if (t > slip + 4 * dt) {
      EXPECT_NEAR(feet, -mu * m * g, 1e-3 * mu * m * g) << t;
    }
  }
  EXPECT_GE(first, slip);
  EXPECT_LE(first, slip + 4 * dt);
  // sliding at (F - mu m g) / m under the full push (0.125-0.16 s), the beam held
  const auto &x0 = row_at(rows, 0.125), &x2 = row_at(rows, 0.16);
  const auto& x1 = row_at(rows, 0.5 * (x0.at("t") + x2.at("t")));
  const double h = x1.at("t") - x0.at("t");
  const double a = (x2.at("block_x") - 2 * x1.at("block_x") + x0.at("block_x")) / (h * h);
  EXPECT_NEAR(a, (0.15 - mu * m * g) / m, 1e-3 * (0.15 - mu * m * g) / m);
  EXPECT_LT(std::abs(x2.at("beam_x") - x0.at("beam_x")), 1e-7);
  // the feet's rows (and the block's on the beam) solved as one problem: no passes
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0);
  EXPECT_EQ(s["elastic_contact"]["shared_passes"], 0);
  EXPECT_EQ(s["elastic_contact"]["shared_unsettled"], 0);
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(ran.out);
}

// samples/rubber_blocks_pushed_on_loose_mat.vp: two rubber blocks on a loose rubber mat
// (three floating elastic bodies), one pushed with a force that grows to 0.15 N over 0.3 s.
// After the pusher has struck the other block, the mat's friction holds both until the push
// reaches 2 mu m g, the pusher's contacts answering the push (one step behind it); then
// they slide together at (F - 2 mu m g) / 2m, the table's friction holding the mat. (Such
// runs were stopped when the blocks met, exit 3.)
TEST(Cli, TheRubberBlocksPushedOnALooseMatSampleHoldThenSlide) {
  const SampleRun ran = run_sample("rubber_blocks_pushed_on_loose_mat");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const auto& s = ran.summary;
  ASSERT_EQ(ran.build["bodies"][2]["name"], "pusher");
  const double m = ran.build["bodies"][2]["mass"].get<double>(), g = 9.81, mu = 0.5;
  const double rate = 0.15 / 0.3, dt = s["time_step"].get<double>();
  const auto rows = read_history(ran.out / "history.csv");
  // held (the push reaches 2 mu m g at 0.173 s): still to 2e-7 m (17 nm found; 42 nm stage by
  // stage), the pusher's contacts answering the push of a step before to 1e-3 of it
  const auto &held0 = row_at(rows, 0.15), &held1 = row_at(rows, 0.17);
  for (const std::string body : {"pusher", "pushed"})
    EXPECT_LT(std::abs(held1.at(body + "_x") - held0.at(body + "_x")), 2e-7) << body;
  for (const auto& row : rows) {
    if (const double t = row.at("t"); t >= 0.15 && t <= 0.17) {
      EXPECT_NEAR(row.at("pusher_cx"), -rate * (t - dt), 1e-3 * rate * t) << t;
    }
  }
  // sliding under the growing push, the mat's contacts carry the pusher's weight to 1e-2
  // (1.4e-3 found; 2.8e-3 stage by stage; with the stages' forces on the blocks a step late they
  // swung between 0 and 2.7 times it, and the pusher hopped)
  for (const auto& row : rows) {
    if (const double t = row.at("t"); t >= 0.2 && t <= 0.29) {
      EXPECT_NEAR(row.at("pusher_cz"), m * g, 1e-2 * m * g) << t;
    }
  }
  // sliding together under the whole push (0.3-0.35 s): (F - 2 mu m g) / 2m (6.6e-6 found;
  // the middle row half a step off the middle)
  const auto &x0 = row_at(rows, 0.3), &x1 = row_at(rows, 0.325), &x2 = row_at(rows, 0.35);
  const double h1 = x1.at("t") - x0.at("t"), h2 = x2.at("t") - x1.at("t");
  const double a = (0.15 - 2 * mu * m * g) / (2 * m);
  for (const std::string body : {"pusher", "pushed"}) {
    const std::string x = body + "_x";
    EXPECT_NEAR(2 * ((x2.at(x) - x1.at(x)) / h2 - (x1.at(x) - x0.at(x)) / h1) / (h1 + h2), a,
                1e-3 * a)
        << body;
  }
  // the mat held on the table (its frame shifts as the blocks' friction shears it: 38 nm)
  EXPECT_LT(std::abs(rows.back().at("mat_x") - rows.front().at("mat_x")), 1e-6);
  EXPECT_LT(s["elastic_contact"]["max_penetration"].get<double>(), 1e-5);
  // the three solved as one (the mat's rows on both blocks, the blocks' pair), no passes
  EXPECT_GT(s["elastic_contact"]["joint_solves"].get<long>(), 0);
  EXPECT_EQ(s["elastic_contact"]["shared_passes"].get<long>(), 0);
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(ran.out);
}

// samples/rubber_block_on_loose_mat.vp: a loose rubber mat dropped flat onto the table and a
// block dropped onto it, nothing gripping either: both land and come to rest flat, each on
// what is under it (the mat at its half-thickness, the block on the mat, to 1e-6 m), the
// contacts carrying the mat's and the block's weights, and their steps are then skipped.
// (Measured from the element at its centroid, the mat's landing threw it off: exit 3.)
TEST(Cli, TheRubberBlockOnALooseMatSampleRestsFlat) {
  const SampleRun ran = run_sample("rubber_block_on_loose_mat");
  ASSERT_EQ(ran.result.code, 0) << ran.result.output;
  const fs::path& out = ran.out;
  const auto& s = ran.summary;
  const auto& b = ran.build;
  ASSERT_EQ(b["bodies"][1]["name"], "mat");
  const double big_m = b["bodies"][1]["mass"].get<double>(),
               m = b["bodies"][2]["mass"].get<double>(), g = 9.81;
  const auto rows = read_history(out / "history.csv");
  const auto& end = rows.back();
  EXPECT_NEAR(end.at("mat_z"), 0.005, 1e-6);
  EXPECT_NEAR(end.at("block_z"), 0.020, 1e-6);
  // the table under the mat and the mat under the block
  EXPECT_NEAR(end.at("contact_force"), (big_m + 2 * m) * g, 1e-4 * (big_m + 2 * m) * g);
  for (const std::string body : {"mat", "block"})
    EXPECT_LT(std::abs(end.at(body + "_z") - row_at(rows, 0.15).at(body + "_z")), 1e-9) << body;
  // at rest from about t = 0.06 s, both bodies' steps skipped from there
  for (const auto& row : rows)
    if (row.at("t") >= 0.1) {
      EXPECT_EQ(row.at("kinetic_energy"), 0) << row.at("t");
    }
  EXPECT_GT(s["elastic_contact"]["resting_steps"].get<double>(), 1000);  // of 2 x 1,000
  EXPECT_LT(s["elastic_contact"]["max_penetration"].get<double>(), 1e-6);
  EXPECT_EQ(s["status"], "ok");
  fs::remove_all(out);
}

// Two elastic blocks started 3 mm inside each other (mesh 4 and 3 mm): the contact points
// reach a quarter of the mesh size below a surface, so the run would let them pass through
// each other unseen; it stops at its start instead, naming them (exit 3).
TEST(Cli, RunStopsTwoElasticBodiesStartedInsideEachOther) {
  const fs::path out = fresh_dir("elastic_overlap");
  const fs::path script =
      write_script("vproto_cli_elastic_overlap.vp",
                   "units length=mm force=N;\n"
                   "material soft { E = 10MPa; nu = 0.3; density = 1000kg/m^3; friction = 0; }\n"
                   "elastic body top (material=soft, mesh_size=4mm, element=tet10) {\n"
                   "  translate([-10mm, -10mm, -3mm]) box([20mm, 20mm, 20mm]); }\n"
                   "elastic body bottom (material=soft, mesh_size=3mm, element=tet10) {\n"
                   "  translate([-10mm, -10mm, -30mm]) box([20mm, 20mm, 30mm]); }\n"
                   "fix bottom region=box([-11mm, -11mm, -31mm], [11mm, 11mm, -29.9mm]);\n"
                   "grip top region=box([-11mm, -11mm, 16.9mm], [11mm, 11mm, 18mm]);\n"
                   "move top by=[0, 0, -0.05mm] over=1s;\n"
                   "simulate(mode=quasistatic, duration=1s, frames=5);\nexport(format=none);\n");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render");
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("elastic bodies 'top' and 'bottom' overlap where the run starts"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("move them apart"), std::string::npos) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["status"], "failed");
  fs::remove_all(out);
}

// A free rubber cube dropped 2 mm onto a clamped rubber pad: the cube's floating frame owns
// the pair (its rows carry its mobility and both bodies' compliances), the pad deforms
// quasi-statically under the reactions (a massless spring, as under a falling rigid body).
// It lands once, when free fall says, and rests: the contact carries its weight and the
// clamp both weights.
TEST(Cli, RunDropsAFreeRubberCubeOnAClampedRubberPad) {
  const fs::path out = fresh_dir("rubber_pair");
  const fs::path script = write_script(
      "vproto_cli_rubber_pair.vp",
      "units length=mm force=N;\n"
      "material rubber { E = 2MPa; nu = 0.45; density = 1100kg/m^3; friction = 0.5; }\n"
      "gravity [0, 0, -9.81m/s^2];\n"
      "elastic body cube (material=rubber, mesh_size=5mm, element=tet10) {\n"
      "  translate([-10mm, -10mm, 2mm]) box([20mm, 20mm, 20mm]); }\n"
      "elastic body pad (material=rubber, mesh_size=5mm, element=tet10) {\n"
      "  translate([-20mm, -20mm, -10mm]) box([40mm, 40mm, 10mm]); }\n"
      "fix pad region=box([-21mm, -21mm, -11mm], [21mm, 21mm, -9.9mm]);\n"
      "simulate(mode=dynamic, duration=0.15s, frames=31);\nexport(format=none);\n");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto build = nlohmann::json::parse(std::ifstream(out / "build.json"));
  const double cube = build["bodies"][0]["mass"], pad = build["bodies"][1]["mass"];
  ASSERT_EQ(summary["events"].size(), 1u) << summary["events"].dump();  // lands once
  EXPECT_EQ(summary["events"][0]["type"], "contact_added");
  EXPECT_NEAR(summary["events"][0]["t"].get<double>(), std::sqrt(2 * 0.002 / 9.81),
              2 * summary["time_step"].get<double>());
  EXPECT_NE(summary["note"].get<std::string>().find("pad deforms quasi-statically"),
            std::string::npos);
  EXPECT_EQ(summary["elastic_contact"]["unconverged_solves"], 0);
  EXPECT_LT(summary["elastic_contact"]["max_penetration"].get<double>(), 1e-7);
  const auto rows = read_history(out / "history.csv");
  ASSERT_FALSE(rows.empty());
  EXPECT_NEAR(rows.back().at("contact_force"), cube * 9.81, 1e-6 * cube * 9.81);
  EXPECT_NEAR(rows.back().at("pad_rz"), (cube + pad) * 9.81, 1e-6 * (cube + pad) * 9.81);
  EXPECT_LT(rows.back().at("kinetic_energy"), 1e-12);
  EXPECT_NEAR(rows.back().at("cube_z"), 0.01, 1e-5);  // on the pad, not in it
  fs::remove_all(out);
}

// A quasi-static increment that finds no equilibrium at its last cut is kept, counted and
// said: the paw sample's hook at 30 degrees on its 0.1 in elements, pulled back out, where
// the return face's apex passes the catch's lower edge (after 32 passes at a 64th of the
// increment, most of the force is still on rows past the edge; 64 passes leave it so too).
// The warning names the bodies, the time and the finer mesh; at half the mesh size every
// increment settles.
TEST(Cli, AnUnsettledQuasistaticIncrementIsSaidWithItsPlaceAndFix) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path coarse = fresh_dir("paw30"), fine = fresh_dir("paw30_fine");
  const Result r1 =
      run("run " + sample + " -o " + coarse.string() + " --no-render --set hook_angle=30deg");
  ASSERT_EQ(r1.code, 0) << r1.output;
  const auto s1 = nlohmann::json::parse(std::ifstream(coarse / "summary.json"));
  const long unsettled = s1["elastic_contact"]["unsettled_increments"].get<long>();
  ASSERT_GE(unsettled, 1);
  const std::string said = s1["elastic_contact"]["first_unsettled"];
  EXPECT_NE(r1.output.find("warning: " + std::to_string(unsettled) +
                           " quasi-static increment(s) kept unsettled; the first: " + said),
            std::string::npos)
      << r1.output;
  EXPECT_NE(said.find("contact of 'paw' with 'catch' found no equilibrium"), std::string::npos)
      << said;
  EXPECT_NE(said.find("cut to a 64th of it"), std::string::npos) << said;
  EXPECT_NE(said.find("use a finer mesh_size for 'paw' (now 0.00254 m)"), std::string::npos)
      << said;
  // on the way out (1.1 in/s from t = 1 s, the tip 1.1 in down): between the return face's
  // first touch of the catch's lower edge (0.7 in down; the face at x = -0.02 in is 1.75
  // rises above the tip) and a little past its apex (one rise above the tip)
  const auto at = said.find("at t = ");
  ASSERT_NE(at, std::string::npos);
  const double t = std::stod(said.substr(at + 7));
  const double rise = 0.08 / std::tan(M_PI / 6);
  EXPECT_GT(t, 1 + (1.1 - (0.7 + 1.75 * rise)) / 1.1) << said;
  EXPECT_LT(t, 1 + (1.1 - (0.7 + rise)) / 1.1 + 0.02) << said;
  const Result r2 = run("run " + sample + " -o " + fine.string() +
                        " --no-render --quiet --set hook_angle=30deg --set mesh=0.05in");
  ASSERT_EQ(r2.code, 0) << r2.output;
  const auto s2 = nlohmann::json::parse(std::ifstream(fine / "summary.json"));
  EXPECT_EQ(s2["elastic_contact"]["unsettled_increments"], 0);
  EXPECT_FALSE(s2["elastic_contact"].contains("first_unsettled"));
  fs::remove_all(coarse);
  fs::remove_all(fine);
}

// The run's largest stress and strain of an elastic body, where and when, against its
// material's yield (summary.json bodies[].yield, and a warning when passed), anywhere and
// away from contacts (two mesh sizes from every pressed node). In the paw sample the catch's
// edge on the hook concentrates the stress under it; away from it the largest strain is the
// root's bending strain, below LDPE's yield strain (4 %): Bayer's 1.5 h y / l^2 for the hook's
// deflection, at the elements' centroids (a quarter of a 0.1 in element inside the surface
// of the 0.125 in half-thickness, and below the root: 0.75-1). With the catch's face 0.5 in
// inside the hook's reach, the catch stands under the whole paw, which is crushed 0.3 in
// along its 2 in: the stress passes 10 MPa once the paw's mean axial stress E (travel -
// 0.2 in) / 2 in does, if not before, and never before the paw touches.
TEST(Cli, AnElasticBodyPastItsYieldIsSaidWithWhereAndWhen) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path out = fresh_dir("paw_yield");
  const Result ok = run("run " + sample + " -o " + out.string() + " --no-render");
  ASSERT_EQ(ok.code, 0) << ok.output;
  EXPECT_EQ(ok.output.find("passes its material's yield"), std::string::npos) << ok.output;
  auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  auto paw = summary["bodies"][0];
  ASSERT_EQ(paw["name"], "paw");
  const double e = 0.25e9, strength = 10e6, in = 0.0254;
  EXPECT_FALSE(paw["yield"].contains("exceeded_at"));
  EXPECT_FALSE(paw["yield"]["away_from_contact"].contains("exceeded_at"));
  EXPECT_DOUBLE_EQ(paw["yield"]["strength"].get<double>(), strength);
  EXPECT_DOUBLE_EQ(paw["yield"]["strain"].get<double>(), 0.04);
  const double peak = paw["peak_strain"];
  EXPECT_DOUBLE_EQ(paw["yield"]["strain_ratio"].get<double>(), peak / 0.04);
  EXPECT_DOUBLE_EQ(paw["yield"]["stress_ratio"].get<double>(),
                   paw["peak_von_mises"].get<double>() / strength);
  EXPECT_GE(peak, paw["max_strain"].get<double>());
  const auto away = paw["away_from_contact"];
  const double root = away["peak_strain"], bayer = 1.5 * 0.25 * 0.06 / std::pow(2 - 0.08, 2);
  EXPECT_GT(root, 0.75 * bayer);
  EXPECT_LT(root, bayer);
  EXPECT_LE(root, peak);
  EXPECT_GT(away["peak_strain_at"][2].get<double>(), (2 - 0.15) * in);  // at the root
  // (gripped there, not a sharp inside corner: the same away from corners)
  EXPECT_FALSE(away["peak_strain_at_sharp_corner"].get<bool>());
  EXPECT_EQ(paw["away_from_contact_and_corners"]["peak_strain"].get<double>(), root);
  const double when = away["peak_strain_time"];
  EXPECT_GT(when, 0.2 / 1.1);  // after the hook meets the catch, going in
  EXPECT_LT(when, 1.0);
  fs::remove_all(out);

  const Result crushed = run("run " + sample + " -o " + out.string() +
                             " --no-render --set interference=0.5in --set travel=0.5in");
  ASSERT_EQ(crushed.code, 0) << crushed.output;
  summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  paw = summary["bodies"][0];
  ASSERT_TRUE(paw["yield"]["away_from_contact"]["exceeded_at"].is_number());
  const double at = paw["yield"]["away_from_contact"]["exceeded_at"], dt = summary["time_step"];
  const double touch = 0.2 / 0.5, mean_yields = (0.2 + 2 * strength / e / in) / 0.5;
  EXPECT_GT(at, touch);
  EXPECT_LE(at, mean_yields + dt);
  EXPECT_LE(paw["yield"]["exceeded_at"].get<double>(), at);
  // the warning's time is where it passes the yield away from the hook's inside corners too
  const double in_body = paw["yield"]["away_from_contact_and_corners"]["exceeded_at"];
  EXPECT_GE(in_body, at);
  EXPECT_LE(in_body, mean_yields + dt);
  // at full travel the mean axial stress is E 0.3 in / 2 in
  EXPECT_GT(paw["away_from_contact"]["peak_von_mises"].get<double>(), 0.8 * e * 0.3 / 2);
  std::ostringstream said;
  said << "warning: elastic body 'paw' passes its material's yield at t = " << in_body << " s";
  EXPECT_NE(crushed.output.find(said.str()), std::string::npos) << crushed.output;
  EXPECT_NE(crushed.output.find("x yield_strength 10 MPa"), std::string::npos) << crushed.output;
  EXPECT_NE(crushed.output.find("choose a material that takes it"), std::string::npos)
      << crushed.output;
  fs::remove_all(out);
}

// A static run reports the same peaks against the yield: the load ramps from 0 to 1 over
// the duration and the response is linear, so the steel cantilever (A36: 250 MPa) loaded
// 60 times over passes its yield where the load factor is the yield strength over the
// peak stress, at the clamped root (Euler-Bernoulli: M c / I = 6000 N m 0.025 m / I =
// 288 MPa at the surface; the centroids lie inside it).
TEST(Cli, AStaticRunSaysWhereItsLoadPassesTheYield) {
  std::ifstream in(std::string(VPROTO_SAMPLES) + "/cantilever.vp");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const fs::path out = fresh_dir("cantilever_yield");
  for (const double load : {100.0, 6000.0}) {
    std::string script = text;
    const std::string from = "force beam [0, 0, -100]";
    ASSERT_NE(script.find(from), std::string::npos);
    script.replace(script.find(from), from.size(),
                   "force beam [0, 0, -" + std::to_string(static_cast<int>(load)) + "]");
    const fs::path file = write_script("vproto_cli_cantilever_yield.vp", script);
    const Result r = run("run " + file.string() + " -o " + out.string() + " --no-render");
    ASSERT_EQ(r.code, 0) << r.output;
    const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
    const auto beam = summary["bodies"][0];
    const double peak = beam["peak_von_mises"], strength = 250e6;
    EXPECT_DOUBLE_EQ(beam["yield"]["stress_ratio"].get<double>(), peak / strength);
    EXPECT_GT(peak, 0.8 * load * 1.0 * 0.025 / (std::pow(0.05, 4) / 12));
    EXPECT_LT(peak, load * 1.0 * 0.025 / (std::pow(0.05, 4) / 12));
    EXPECT_LT(beam["peak_von_mises_at"][0].get<double>(), 0.05);  // at the root
    if (load < 1000) {
      EXPECT_FALSE(beam["yield"].contains("exceeded_at"));
      EXPECT_EQ(r.output.find("passes its material's yield"), std::string::npos) << r.output;
      continue;
    }
    const double at = beam["yield"]["exceeded_at"];
    const double ratio = std::max(beam["yield"]["stress_ratio"].get<double>(),
                                  beam["yield"]["strain_ratio"].get<double>());
    EXPECT_NEAR(at, 1.0 / ratio, 1e-12);  // duration 1 s
    EXPECT_DOUBLE_EQ(beam["yield"]["away_from_contact"]["exceeded_at"].get<double>(), at);
    EXPECT_NE(r.output.find("warning: elastic body 'beam' passes its material's yield at t = "),
              std::string::npos)
        << r.output;
  }
  fs::remove_all(out);
}

// render(field=strain): the largest principal strain, nodal-averaged, in the frames and the
// volume meshes of a dynamic or quasistatic run; a scene with no elastic body refuses it
// as it does von_mises.
TEST(Cli, TheFramesAndMeshesCanShowTheStrain) {
  std::ifstream in(std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& [from, to] :
       {std::pair<std::string, std::string>{"field=von_mises", "field=strain"},
        {"export(format=none)", "export(format=vtu)"}}) {
    ASSERT_NE(text.find(from), std::string::npos) << from;
    text.replace(text.find(from), from.size(), to);
  }
  const fs::path file = write_script("vproto_cli_paw_strain.vp", text);
  const fs::path out = fresh_dir("paw_strain");
  const Result r =
      run("run " + file.string() + " -o " + out.string() + " --frames 5 --size 320x240 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(out / "frames" / "frame_0004.png"));
  std::ifstream vtu(out / "meshes" / "paw_0002.vtu");
  const std::string mesh((std::istreambuf_iterator<char>(vtu)), std::istreambuf_iterator<char>());
  EXPECT_NE(mesh.find("Name=\"strain\""), std::string::npos);
  fs::remove_all(out);
  const fs::path rigid =
      write_script("vproto_cli_rigid_strain.vp",
                   "rigid body r (material=steel) { box(1); }\nfix r;\nsimulate(duration=0.01s, "
                   "frames=2);\nrender(field=strain);\n");
  const Result refused = run("run " + rigid.string() + " -o " + out.string() + " --quiet");
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_NE(refused.output.find("render field=strain, but no body has it"), std::string::npos)
      << refused.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

// A steel L-bracket (a 20 mm square leg on a 60 x 20 x 20 mm foot, the foot held at its
// bottom) pushed sideways at the leg's top: the inside corner where the leg meets the foot
// is a sharp re-entrant edge, where the linear-elastic stress is singular. Refined from 4 to
// 2 mm its peak there grows by a fifth (300 -> 369 MPa at 5 kN), while away from it (0.4 of
// the thinnest wall, 8 mm, or two elements) the peak converges to the beam's bending stress
// F (80 mm - z) c / I at its place (186 -> 194 MPa). At 5 kN only the corner passes
// A36's 250 MPa and the warning says so; at 8 kN the leg does.
TEST(Cli, AYieldOnlyAtASharpInsideCornerIsToldFromTheBodys) {
  const fs::path file = write_script("vproto_cli_l_bracket.vp", R"(units length=mm force=N;
param push = 5000N;
param size = 4mm;
elastic body bracket (material=steel, mesh_size=size, element=tet10) {
  box([60, 20, 20]);
  translate([0, 0, 20]) box([20, 20, 60]);
}
fix bracket region=box([-1, -1, -1], [61, 21, 0.001]);
force bracket [-push, 0, 0] region=box([-1, -1, 79.999], [21, 21, 81]);
simulate(mode=static, frames=2, duration=1s);
export(format=none);
)");
  const fs::path out = fresh_dir("l_bracket");
  struct Peaks {
    double corner, body, body_x, body_z;
    bool corner_flag, body_flag;
    double hot;  // the hot-spot stress extrapolated to the corner
  };
  auto run_at = [&](const std::string& push, const std::string& size, std::string* said) {
    const Result r = run("run " + file.string() + " -o " + out.string() +
                         " --no-render --set push=" + push + " --set size=" + size);
    EXPECT_EQ(r.code, 0) << r.output;
    *said = r.output;
    const auto bracket = nlohmann::json::parse(std::ifstream(out / "summary.json"))["bodies"][0];
    const auto away = bracket["away_from_contact"], body = bracket["away_from_contact_and_corners"];
    return Peaks{away["peak_von_mises"],
                 body["peak_von_mises"],
                 body["peak_von_mises_at"][0],
                 body["peak_von_mises_at"][2],
                 away["peak_von_mises_at_sharp_corner"],
                 body["peak_von_mises_at_sharp_corner"],
                 bracket["sharp_corner_hot_spot"]["peak_von_mises"]};
  };
  std::string said;
  const Peaks coarse = run_at("5000N", "4mm", &said);
  EXPECT_TRUE(coarse.corner_flag);
  EXPECT_FALSE(coarse.body_flag);
  EXPECT_GT(coarse.corner, 250e6);
  EXPECT_LT(coarse.body, 250e6);
  EXPECT_NE(said.find("warning: elastic body 'bracket' passes its material's yield only at a "
                      "sharp inside corner at t = "),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("below it: round the corner with a fillet"), std::string::npos) << said;
  const Peaks fine = run_at("5000N", "2mm", &said);
  EXPECT_GT(fine.corner, 1.15 * coarse.corner);  // singular
  EXPECT_LT(fine.body, 1.06 * coarse.body);      // converging
  // extrapolated to the corner from the leg's face (0.4 t and 1.0 t up it), the stress is
  // the beam's at its root, M c / I = 5 kN x 60 mm x 10 mm / (20^4 / 12 mm^4) = 225 MPa,
  // and the same at both meshes (229.5 and 226.6 MPa measured)
  for (const Peaks& p : {coarse, fine}) EXPECT_NEAR(p.hot, 225e6, 0.03 * 225e6);
  EXPECT_NEAR(fine.hot, coarse.hot, 0.02 * coarse.hot);
  for (const Peaks& p : {coarse, fine}) {
    // M c / I at the element's centroid (c from the leg's middle plane, x = 10 mm)
    const double beam =
        5000 * (0.08 - p.body_z) * std::abs(p.body_x - 0.01) / std::pow(0.02, 4) * 12;
    EXPECT_GT(p.body, 0.9 * beam);
    EXPECT_LT(p.body, 1.1 * beam);
  }
  // at 6 kN the leg's body stays below the yield (223 MPa) and the corner's hot-spot stress
  // passes it (275 MPa): a fillet alone will not do
  const Peaks six = run_at("6000N", "4mm", &said);
  EXPECT_LT(six.body, 250e6);
  EXPECT_GT(six.hot, 250e6);
  EXPECT_NE(said.find("only at a sharp inside corner"), std::string::npos) << said;
  EXPECT_NE(said.find("past the yield even so, so a fillet alone will not keep the corner"),
            std::string::npos)
      << said;
  const Peaks hard = run_at("8000N", "4mm", &said);
  EXPECT_GT(hard.body, 250e6);
  EXPECT_NE(said.find("warning: elastic body 'bracket' passes its material's yield at t = "),
            std::string::npos)
      << said;
  EXPECT_NE(said.find("linear elasticity does not hold there"), std::string::npos) << said;
  fs::remove_all(out);
}

// The warning's advice taken (samples/l_bracket_corner.vp, the L-bracket above): its inside
// corner rounded by a fillet of half the leg's thickness (fillet(r, h) united into the
// corner), it has no sharp
// corner left and its peak converges (at 5 kN 231 and 248 MPa at 3 and 2 mm, where the
// sharp corner's went 320 and 369 MPa), a stress concentration of about 1.1 on the beam's
// M c / I at the root. At 4.5 kN, where the sharp corner passes the yield (332 MPa at 2 mm),
// the rounded one stays below it (223 MPa) and nothing is warned of.
TEST(Cli, AFilletedCornerConvergesAndNoLongerWarns) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/l_bracket_corner.vp";
  const fs::path out = fresh_dir("l_fillet");
  const double beam = 4500 * 0.06 * 0.01 / (std::pow(0.02, 4) / 12);  // M c / I, 202.5 MPa
  std::vector<double> peaks;
  for (const char* size : {"3mm", "2mm"}) {
    const Result r = run("run " + sample + " -o " + out.string() +
                         " --no-render --set fillet_r=10mm --set push=4500N --set size=" + size);
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_EQ(r.output.find("warning: elastic body"), std::string::npos) << r.output;
    const auto bracket = nlohmann::json::parse(std::ifstream(out / "summary.json"))["bodies"][0];
    EXPECT_FALSE(bracket.contains("sharp_corner_hot_spot"));
    EXPECT_FALSE(bracket["peak_von_mises_at_sharp_corner"].get<bool>());
    EXPECT_FALSE(bracket["yield"].contains("exceeded_at"));
    // on the fillet: x and z between the corner's 20 and 30 mm
    for (const int k : {0, 2}) {
      EXPECT_GT(bracket["peak_von_mises_at"][k].get<double>(), 0.018);
      EXPECT_LT(bracket["peak_von_mises_at"][k].get<double>(), 0.031);
    }
    peaks.push_back(bracket["peak_von_mises"]);
  }
  EXPECT_LT(peaks[1], 1.10 * peaks[0]);  // converging (the sharp corner: 1.15)
  for (const double p : peaks) {
    EXPECT_GT(p, 1.0 * beam);
    EXPECT_LT(p, 1.25 * beam);
  }
  fs::remove_all(out);
}

// render(field=yield): each elastic body's stress and strain as a fraction of its
// material's yield (the larger of von Mises / yield_strength and strain / yield_strain), on
// a scale fixed at the yield, red past it; exported volume meshes carry it as yield_ratio.
// The steel cantilever at 6000 N passes its yield at the root (288 MPa against 250 MPa at
// the surface): the last frame has red near the root and none at the tip; at 100 N no
// frame has any. A material that gives no yield is refused at its body's line.
TEST(Cli, TheYieldFieldShowsWhereABodyPassesItsYield) {
  std::ifstream in(std::string(VPROTO_SAMPLES) + "/cantilever.vp");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (const auto& [from, to] : {std::pair<std::string, std::string>{"field=von_mises, camera=iso",
                                                                     "field=yield, camera=front"},
                                 {"size=[1280, 720]", "size=[640, 240]"},
                                 {"frames=30", "frames=3"}}) {
    ASSERT_NE(text.find(from), std::string::npos) << from;
    text.replace(text.find(from), from.size(), to);
  }
  const fs::path out = fresh_dir("cantilever_yield_field");
  auto red_columns = [](const fs::path& png) {
    const vproto::ui_batch::Image img = vproto::ui_batch::read_png(png.string());
    std::vector<int> columns;  // the image's columns with a red pixel, left of the legend
    for (int x = 0; x < img.width * 3 / 4; ++x)
      for (int y = 0; y < img.height; ++y) {
        const std::uint8_t* p = img.at(x, y);
        if (p[0] > 100 && 2 * p[1] < p[0] && 2 * p[2] < p[0]) {
          columns.push_back(x);
          break;
        }
      }
    return columns;
  };
  for (const int load : {100, 6000}) {
    std::string script = text;
    const std::string from = "force beam [0, 0, -100]";
    script.replace(script.find(from), from.size(),
                   "force beam [0, 0, -" + std::to_string(load) + "]");
    const fs::path file = write_script("vproto_cli_cantilever_yield_field.vp", script);
    const Result r = run("run " + file.string() + " -o " + out.string() + " --quiet");
    ASSERT_EQ(r.code, 0) << r.output;
    EXPECT_TRUE(red_columns(out / "frames" / "frame_0000.png").empty());
    const std::vector<int> red = red_columns(out / "frames" / "frame_0002.png");
    if (load == 100) {
      EXPECT_TRUE(red.empty()) << red.size();
    } else {
      // the front view has the beam across the image, clamped at the left: red at the root
      ASSERT_FALSE(red.empty());
      EXPECT_LT(red.back(), 640 / 4) << red.front() << "-" << red.back();
    }
    std::ifstream vtu(out / "meshes" / "beam_0002.vtu");
    const std::string mesh((std::istreambuf_iterator<char>(vtu)), std::istreambuf_iterator<char>());
    EXPECT_NE(mesh.find("Name=\"yield_ratio\""), std::string::npos);
    fs::remove_all(out);
  }
  std::string plain = text;
  plain.replace(plain.find("material=steel"), 14, "material=mild");
  plain =
      "units length=mm force=N;\nmaterial mild { E = 210GPa; nu = 0.3; density = 7850kg/m^3; }\n" +
      plain.substr(plain.find('\n', plain.find("units ")) + 1);
  const fs::path file = write_script("vproto_cli_cantilever_no_yield.vp", plain);
  const Result refused = run("run " + file.string() + " -o " + out.string() + " --quiet");
  EXPECT_EQ(refused.code, 2) << refused.output;
  EXPECT_NE(refused.output.find("vproto_cli_cantilever_no_yield.vp:"), std::string::npos)
      << refused.output;
  EXPECT_NE(refused.output.find("'mild', which gives neither"), std::string::npos)
      << refused.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

// The paw of samples/paw_quasistatic.vp pushed over a steel catch that is an elastic body
// (clamped at its back) instead of a rigid one: friction, sliding and a sharp edge riding
// over a face between two FE surfaces. The catch is 800 times stiffer than the paw, so the
// forces are the rigid catch's: the sliding and pull-out plateaus to 0.1 %, and the peaks
// over the lead and return faces to 2 %. Both peaks are where an edge leaves a face: the
// increments in which the push or the pull lets go, or whose rows do not settle, are
// halved until the release is found (rigid catch 7.95 and 3.56 N, elastic catch 7.88 and
// 3.56 N, 8.02 and 3.57 N converged at 25 times finer increments; before, 8.44 and 4.06 N
// with the rigid catch, 7.97 N and 3 % with the elastic one).
TEST(Cli, APawOverAnElasticSteelCatchFeelsWhatARigidCatchGives) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  std::ifstream in(sample);
  std::stringstream text;
  text << in.rdbuf();
  std::string script = text.str();
  auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = script.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    script.replace(at, from.size(), to);
  };
  replace("rigid body catch (material=abs) {",
          "elastic body catch (material=steel, mesh_size=mesh, element=tet10) {");
  replace("fix catch;", "fix catch region=box([-1.1in, -0.6in, -0.8in], [0.1in, 0.6in, -0.69in]);");
  const fs::path elastic = write_script("vproto_cli_paw_elastic_catch.vp", script);
  const fs::path out_rigid = fresh_dir("paw_rigid_catch"),
                 out_elastic = fresh_dir("paw_elastic_catch");
  const Result r1 = run("run " + sample + " -o " + out_rigid.string() + " --no-render --quiet");
  ASSERT_EQ(r1.code, 0) << r1.output;
  const Result r2 =
      run("run " + elastic.string() + " -o " + out_elastic.string() + " --no-render --quiet");
  ASSERT_EQ(r2.code, 0) << r2.output;
  const auto rigid = read_history(out_rigid / "history.csv");
  const auto soft = read_history(out_elastic / "history.csv");
  // (increments are cut where an edge leaves a face, in each run where its own rows ask:
  // the rows are compared where both runs have them)
  std::map<long, std::size_t> soft_at;
  for (std::size_t k = 0; k < soft.size(); ++k) soft_at[std::lround(soft[k].at("t") * 1e6)] = k;
  int plateau = 0;
  for (const auto& row : rigid) {
    const double t = row.at("t");
    // the apex on the catch's face, going in (0.3-0.7 s) and coming out (1.35-1.75 s)
    if ((t > 0.3 && t < 0.7) || (t > 1.35 && t < 1.75)) {
      const auto k = soft_at.find(std::lround(t * 1e6));
      ASSERT_NE(k, soft_at.end()) << t;
      for (const char* column : {"paw_rx", "paw_rz"})
        EXPECT_NEAR(soft[k->second].at(column), row.at(column), 1e-3 * std::abs(row.at(column)))
            << column << " at " << t;
      ++plateau;
    }
  }
  EXPECT_GT(plateau, 50);
  // the catch carries what the grip applies (to 1e-8 N: the grip's reaction sums nodal forces
  // of order 1e4 N, K times the drive's travel, whose rounding left 3.5e-9 N where nothing
  // touched, at t = 1 s, on the mesh of the canonically ordered CSG; 1e-9 N on the one before)
  for (const auto& row : soft)
    EXPECT_NEAR(row.at("catch_rz"), -row.at("paw_rz"), 1e-8) << row.at("t");
  const auto s_rigid = nlohmann::json::parse(std::ifstream(out_rigid / "summary.json"));
  const auto s_soft = nlohmann::json::parse(std::ifstream(out_elastic / "summary.json"));
  for (const char* peak : {"peak_push", "peak_pull"}) {
    const double a = s_rigid["reaction_curves"]["paw"][peak],
                 b = s_soft["reaction_curves"]["paw"][peak];
    EXPECT_NEAR(b, a, 0.02 * std::abs(a)) << peak;
  }
  EXPECT_EQ(s_soft["elastic_contact"]["unconverged_solves"], 0);
  // every increment settles: the paw's points that the catch's surface no longer has where
  // an increment ends it (past its edges) go, and the increment is solved again without them
  // (kept, five increments were still unsettled at a 64th of an increment)
  for (const auto* s : {&s_rigid, &s_soft}) {
    EXPECT_EQ((*s)["elastic_contact"]["unsettled_increments"], 0);
    EXPECT_FALSE((*s)["elastic_contact"].contains("first_unsettled"));
  }
  for (const auto* s : {&s_rigid, &s_soft})
    EXPECT_GT((*s)["elastic_contact"]["cut_increments"].get<long>(), 0);
  // and nothing passes through: the points are taken again where the surfaces, turning and
  // sliding over each other, end each step (without that, 25 um as the return face leaves);
  // what is left is below the depth at which a point joins the rows, 1e-3 of the mesh size
  // (1.9 um, where the return face leaves the catch's edge)
  EXPECT_LT(s_soft["elastic_contact"]["max_penetration"].get<double>(), 1e-3 * 0.1 * 0.0254);
  fs::remove_all(out_rigid);
  fs::remove_all(out_elastic);
}

// A run owns its output folder: what an earlier run left there goes (an old "ok"
// summary.json, frames beyond this run's, a killed run's half-written file; issue 13),
// other files stay, and a second run cannot write into it while the first holds it.
TEST(Cli, RunClearsAnEarlierRunsOutputsAndLocksItsFolder) {
  const fs::path script =
      write_script("vproto_cli_folder.vp",
                   "rigid body b (material=steel) { box(0.1); }\ngravity [0, 0, -9.81];\n"
                   "simulate(duration=0.1s, frames=3);\nrender(size=[64, 48]);\n");
  const fs::path out = fresh_dir("folder");
  fs::create_directories(out / "frames");
  std::ofstream(out / "summary.json") << "{\"status\": \"ok\", \"stale\": true}\n";
  std::ofstream(out / "frames" / "frame_0099.png") << "old";
  std::ofstream(out / ".history.csv.tmp4242") << "half";
  std::ofstream(out / "notes.txt") << "mine";
  const Result r = run("run " + script.string() + " -o " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_FALSE(summary.contains("stale"));
  EXPECT_FALSE(fs::exists(out / "frames" / "frame_0099.png"));
  EXPECT_TRUE(fs::exists(out / "frames" / "frame_0002.png"));
  EXPECT_FALSE(fs::exists(out / ".history.csv.tmp4242"));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));  // not vproto's
  // held by another run: refused, nothing touched
  const int fd = ::open((out / ".vproto.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const Result held = run("run " + script.string() + " -o " + out.string() + " --quiet");
  EXPECT_EQ(held.code, 2) << held.output;
  EXPECT_NE(held.output.find("another vproto run is writing to this folder"), std::string::npos)
      << held.output;
  EXPECT_TRUE(fs::exists(out / "frames" / "frame_0002.png"));
  ::close(fd);
  EXPECT_EQ(run("run " + script.string() + " -o " + out.string() + " --quiet").code, 0);
  fs::remove_all(out);
}

// The stress suite: every scene ends as required (the right figure, or a clean refusal
// naming the cause), with nothing non-finite in any output.
TEST(Cli, BenchStressScenesAllGoAsRequired) {
  const fs::path out = fresh_dir("stress");
  const Result r = run("bench --stress --quick -o " + out.string() + " --quiet");
  const auto doc = nlohmann::json::parse(std::ifstream(out / "stress.json"));
  for (const auto& row : doc["scenes"])
    EXPECT_TRUE(row["correct"].get<bool>()) << row["scene"] << ": " << row["why"];
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_GE(doc["scenes"].size(), 30u);
  EXPECT_EQ(doc["failed"], 0);
  EXPECT_TRUE(fs::exists(out / "stress.md"));
  fs::remove_all(out);
}

TEST(Cli, RunRejectsWhatItCannotDoAndWritesNothing) {
  const fs::path out = fresh_dir("norun");
  // an import that cannot be read is named at its place in the script (issue 13)
  const fs::path garbage = fs::temp_directory_path() / "vproto_cli_garbage.stl";
  std::ofstream(garbage) << "solid x\nfacet garbage\n";
  const fs::path importing =
      write_script("vproto_cli_import.vp",
                   "rigid body b (material=steel) {\n  import(\"" + garbage.string() + "\");\n}\n");
  const Result unread = run("run " + importing.string() + " -o " + out.string());
  EXPECT_EQ(unread.code, 2);
  EXPECT_NE(unread.output.find("vproto_cli_import.vp:2:3: error: import(): cannot read"),
            std::string::npos)
      << unread.output;
  EXPECT_FALSE(fs::exists(out));
  fs::remove(garbage);
  const fs::path rigid =
      write_script("vproto_cli_rigid.vp",
                   "rigid body a (material=steel) { box(1); }\nrender(field=von_mises);\n");
  const Result field = run("run " + rigid.string() + " -o " + out.string());
  EXPECT_EQ(field.code, 2);
  EXPECT_NE(field.output.find("no body has it"), std::string::npos) << field.output;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run("run " + rigid.string() + " -o " + out.string() + " --size 0x0").code, 2);
  EXPECT_EQ(run("run " + rigid.string() + " -o " + out.string() + " --size 100000x100000").code, 2);
  EXPECT_EQ(run("run " + rigid.string() + " -o " + out.string() + " --frames 0").code, 2);
  EXPECT_EQ(run("run " + rigid.string() + " -o " + out.string() + " --duration -1s").code, 2);
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run("run " + rigid.string() + " -o /proc/vproto_out --quiet").code, 2);
}

}  // namespace

namespace {

const std::map<std::string, double>& row_at(const std::vector<std::map<std::string, double>>& rows,
                                            double t) {
  return *std::min_element(rows.begin(), rows.end(), [&](const auto& p, const auto& q) {
    return std::abs(p.at("t") - t) < std::abs(q.at("t") - t);
  });
}

std::vector<std::map<std::string, double>> read_history(const fs::path& file) {
  std::ifstream in(file);
  std::string header, line;
  std::getline(in, header);
  std::vector<std::string> names;
  std::stringstream hs(header);
  for (std::string n; std::getline(hs, n, ',');) names.push_back(n);
  std::vector<std::map<std::string, double>> rows;
  while (std::getline(in, line)) {
    std::stringstream ls(line);
    std::map<std::string, double> row;
    std::string cell;
    for (std::size_t i = 0; i < names.size() && std::getline(ls, cell, ','); ++i) {
      char* end = nullptr;
      const double value = std::strtod(cell.c_str(), &end);
      if (!cell.empty() && end == cell.c_str() + cell.size()) row[names[i]] = value;  // a number
    }
    rows.push_back(row);
  }
  return rows;
}

// The seed's case end to end: the socket slides down on its slider under 50 lbf, both
// paws deflect over the base part's edges (the hook probe moves out by about the 0.1 in
// undercut), snap back, and the socket comes to rest on the base part, which then carries
// the whole push; the grip passes it on.
// An LDPE paw gripped at its top, driven down 0.03 in onto a steel floor 0.02 in below it,
// then held: it starts moving with its grip (no jolt: the grip feels nothing before the
// contact), the grip passes on what the floor pushes back, the contact set stays put while
// it is held (no chatter), and the held force is the paw's axial stiffness times the
// 0.01 in it is squeezed (E A / L; the clamped top and the floor's friction hold its
// Poisson bulge, a few per cent stiffer), steady to 1e-6 of itself.
// A graded mesh is fine where the drives bring a partner, not only where it starts: a
// thick block driven 1 in down onto a floor that starts 0.5 in (many mesh sizes) below
// it is fine at its bottom; driven up, away from the floor, it has no fine zone at all.
// The same script builds the same surface and tet mesh whatever the heap's layout: CGAL's
// corefinement lists its result in an order that follows box addresses, and Mesh_3 meshes
// each order differently (the annular cap below: 93,900 to 99,970 nodes from one binary
// under these settings before the CSG result was put in canonical order).
TEST(Cli, ABodyBuildsTheSameMeshWhateverTheHeapsLayout) {
  const fs::path script =
      write_script("vproto_cli_heap.vp",
                   "units length=mm;\n"
                   "material ldpe { E = 0.25GPa; nu = 0.44; density = 920kg/m^3; }\n"
                   "elastic body cap (material=ldpe, mesh_size=2mm, element=tet4) {\n"
                   "  difference() { cylinder(h=12, r=13, segments=32);\n"
                   "    translate([0, 0, -1]) cylinder(h=11, r=11.2, segments=32); }\n"
                   "  difference() { cylinder(h=1.5, r=11.5, segments=32);\n"
                   "    translate([0, 0, -0.01]) cylinder(h=0.76, r1=11.3, r2=10.6, segments=32);\n"
                   "    translate([0, 0, 0.75]) cylinder(h=0.76, r1=10.6, r2=11.3, segments=32);\n"
                   "    translate([0, 0, -1]) cylinder(h=3.5, r=10.59, segments=32); }\n"
                   "}\n");
  auto bytes = [](const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  };
  std::vector<std::pair<std::string, std::string>> built;  // the STL's and the VTU's bytes
  for (const std::string tunables :
       {"", "glibc.malloc.top_pad=4194304", "glibc.malloc.mmap_threshold=65536"}) {
    const fs::path out = fresh_dir("heap");
    const Result r = shell("GLIBC_TUNABLES=" + tunables + " " + VPROTO_EXE + " build " +
                           script.string() + " -o " + out.string() + " --tets --quiet");
    ASSERT_EQ(r.code, 0) << tunables << ": " << r.output;
    built.emplace_back(bytes(out / "cap.stl"), bytes(out / "cap.vtu"));
    ASSERT_GT(built.back().second.size(), 1000u);
    fs::remove_all(out);
  }
  for (std::size_t i = 1; i < built.size(); ++i) {
    EXPECT_TRUE(built[i].first == built[0].first) << "surface differs, setting " << i;
    EXPECT_TRUE(built[i].second == built[0].second) << "tet mesh differs, setting " << i;
  }
}

TEST(Cli, AGradedMeshIsFineWhereTheDrivesBringAPartner) {
  auto fine_faces = [](const std::string& travel) {
    const fs::path script = write_script(
        "vproto_cli_sweep.vp",
        "units length=in force=lbf;\n"
        "material ldpe { E = 0.25GPa; nu = 0.44; density = 920kg/m^3; }\n"
        "elastic body block (material=ldpe, mesh_size=0.1in, element=tet10) {\n"
        "  box([1in, 1in, 1in]); }\n"
        "rigid body floor (material=steel) { translate([-1in, -1in, -1in]) box([3in, 3in, "
        "0.5in]); }\n"
        "fix floor;\ngrip block region=box([-1in, -1in, 0.99in], [2in, 2in, 1.01in]);\n"
        "move block by=[0, 0, " +
            travel + "] over=1s;\nsimulate(mode=quasistatic, duration=0.01s);\n");
    const fs::path out = fresh_dir("sweep");
    const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
    EXPECT_EQ(r.code, 0) << r.output;
    const auto build = nlohmann::json::parse(std::ifstream(out / "build.json"));
    for (const auto& b : build["bodies"])
      if (b["name"] == "block")
        return b["tet_mesh"]["grading"]["fine_surface_triangles"].get<long>();
    return -1L;
  };
  EXPECT_GT(fine_faces("-1in"), 0);
  EXPECT_EQ(fine_faces("1in"), 0);
}

TEST(Cli, ADrivenPawPressedOnAFloorAndHeldPassesItsForceToItsGrip) {
  const fs::path script = write_script(
      "vproto_cli_press.vp",
      "units length=in force=lbf;\n"
      "material ldpe { E = 0.25GPa; nu = 0.44; density = 920kg/m^3; friction = 0.3; }\n"
      "elastic body paw (material=ldpe, mesh_size=0.25in, element=tet10) {\n"
      "  translate([-0.125in, -0.25in, 0]) box([0.25in, 0.5in, 2in]); }\n"
      "rigid body floor (material=steel) { translate([-1in, -1in, -0.52in]) box([2in, 2in, "
      "0.5in]); }\n"
      "fix floor;\ngrip paw region=box([-1in, -1in, 1.99in], [1in, 1in, 2.01in]);\n"
      "move paw by=[0, 0, -0.03in] over=0.1s;\nmove paw by=[0, 0, 0] over=0.05s;\n"
      "simulate(mode=dynamic, duration=0.15s, frames=4, stiffness_damping=1e-4s);\n");
  const fs::path out = fresh_dir("press");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto rows = read_history(out / "history.csv");
  ASSERT_GT(rows.size(), 1000u);
  const double in = 0.0254, stiffness = 0.25e9 * (0.25 * in) * (0.5 * in) / (2 * in);
  double held = 0, least = 1e300, most = 0;
  std::set<double> held_contacts;
  for (const auto& row : rows) {
    const double f = row.at("contact_force");
    if (row.at("t") > 0.12) {  // held for 20 ms: steady
      least = std::min(least, f);
      most = std::max(most, f);
    }
    if (f == 0) {
      EXPECT_NEAR(row.at("paw_rz"), 0, 1e-6) << row.at("t");  // moving with its grip
      continue;
    }
    // the grip passes it on (but for the paw's own inertia as it first touches, and the
    // step in which the drive stops at once)
    if (std::abs(row.at("t") - 0.1) > 5e-4) {
      EXPECT_NEAR(row.at("paw_rz"), -f, 0.5 + 2e-3 * f) << row.at("t");
    }
    if (row.at("t") > 0.11) {
      held_contacts.insert(row.at("contacts"));
      held = f;
    }
  }
  EXPECT_EQ(held_contacts.size(), 1u);  // no point comes or goes while it is held
  // and the force holds still to 1e-6 of itself: no chatter (without the contact's
  // numerical damping it flipped by 1.7e-4 of itself every step)
  EXPECT_LT(most - least, 1e-6 * held);
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_NE(summary["note"].get<std::string>().find("paw: numerical_damping 0.05"),
            std::string::npos)
      << summary["note"];
  EXPECT_GT(held, stiffness * 0.01 * in);
  EXPECT_LT(held, 1.05 * stiffness * 0.01 * in);
  fs::remove_all(out);
}

TEST(Cli, TheSnapFitSocketSnapsHomeAndRests) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/snapfit.vp";
  const fs::path out = fresh_dir("snaprun");
  const Result r = run("run " + sample + " -o " + out.string() + " --no-render --frames 5 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["status"], "ok");
  ASSERT_FALSE(summary["events"].empty());
  EXPECT_EQ(summary["events"][0]["type"], "contact_added");
  EXPECT_EQ(summary["solver"]["socket"]["factorizations"], 1);
  EXPECT_GT(summary["elastic_contact"]["rigid_only_steps"].get<long>(), 0);  // no FE before
  EXPECT_LT(summary["elastic_contact"]["max_penetration"].get<double>(), 2e-3 * 0.25 * 0.0254);
  const auto rows = read_history(out / "history.csv");
  ASSERT_GT(rows.size(), 100u);
  const double push = 50 * 4.4482216152605, undercut = 0.1 * 0.0254;
  double widest = 0, asymmetry = 0;
  for (const auto& row : rows) {
    widest = std::max(widest, row.at("hook_tip_ux"));
    // the two paws mirror each other all the way (neither hook slips into the base part)
    asymmetry = std::max(asymmetry, std::abs(row.at("hook_tip_ux") + row.at("hook_tip_left_ux")));
  }
  EXPECT_LT(asymmetry, 0.05 * undercut);
  // the insertion force while the lead faces ride over the base part's edges (the first
  // 10 mm of travel) against Bayer's mating force for the two paws, W = 2 P (mu + tan a) /
  // (1 - mu tan a), P = E b h^3 y / (4 l^3): the FE paws on their elastic block are a little
  // softer than the beam's rigid root (references.md: about 18 % for one such paw)
  const double e = 0.25e9, b = 0.5 * 0.0254, l = 2 * 0.0254, mu = 0.3;
  const double p = e * b * b * b * b * (undercut - 0.001 * 0.0254) / (4 * l * l * l);
  const double mating = 2 * p * (mu + 1) / (1 - mu);
  double hump = 0;
  for (const auto& row : rows)
    if (rows.front().at("socket_z") - row.at("socket_z") < 0.010)
      hump = std::max(hump, row.at("socket_cz"));
  EXPECT_GT(hump, 0.75 * mating);
  EXPECT_LT(hump, 1.05 * mating);
  ASSERT_TRUE(summary.contains("insertion_curves"));
  EXPECT_GT(summary["insertion_curves"]["socket"]["peak"].get<double>(), hump);
  // the grip passes on the push alone: the landing's impact stops the socket's mass
  EXPECT_LT(summary["bodies"][0]["peak_reaction"].get<double>(), 1.02 * push);
  // the paws' root strain, away from the contacts, stays below LDPE's yield strain (4 %):
  // Bayer's 1.5 h y / l^2 = 1.9 % at a rigid root for the full undercut, less on the elastic
  // block and at the elements' centroids (1.4 %); under the base part's sharp edges the
  // linear-elastic stress passes 10 MPa, at the hooks, said as a local yield
  const auto socket = summary["bodies"][0];
  const double bayer = 1.5 * b * undercut / (l * l);
  const double root = socket["away_from_contact"]["peak_strain"];
  EXPECT_GT(root, 0.6 * bayer);
  EXPECT_LT(root, bayer);
  EXPECT_FALSE(socket["yield"]["away_from_contact"].contains("exceeded_at"));
  EXPECT_GT(socket["away_from_contact"]["peak_strain_at"][2].get<double>(), -0.25 * 0.0254);
  // the paws' roots are sharp inside corners on the block: away from them too the strain is
  // lower, read lower down the paws
  EXPECT_TRUE(socket["away_from_contact"]["peak_strain_at_sharp_corner"].get<bool>());
  const auto regular = socket["away_from_contact_and_corners"];
  EXPECT_FALSE(regular["peak_strain_at_sharp_corner"].get<bool>());
  EXPECT_LT(regular["peak_strain"].get<double>(), root);
  EXPECT_GT(regular["peak_strain"].get<double>(), 0.3 * bayer);
  // extrapolated to the roots from the paws' inner faces (the hot-spot strain) it is the
  // bending strain at the root: Bayer's 1.5 h y / l^2 for the hook's own deflection y, less
  // the root's rotation on the elastic block (references.md: about 18 %; 1.55 % against
  // 1.81 % measured), at an inner face's root (x = +-4.5 in, z = 0)
  const auto hot = socket["sharp_corner_hot_spot"];
  const double bayer_at_widest = 1.5 * b * widest / (l * l);
  EXPECT_GT(hot["peak_strain"].get<double>(), 0.78 * bayer_at_widest);
  EXPECT_LT(hot["peak_strain"].get<double>(), 0.95 * bayer_at_widest);
  EXPECT_GT(hot["peak_strain"].get<double>(), regular["peak_strain"].get<double>());
  EXPECT_NEAR(std::abs(hot["peak_strain_at"][0].get<double>()), 4.5 * 0.0254, 1e-9);
  EXPECT_NEAR(hot["peak_strain_at"][2].get<double>(), 0, 1e-9);
  EXPECT_FALSE(socket["yield"]["sharp_corner_hot_spot"].contains("exceeded_at"));
  // history.csv has the roots' strain step by step, nothing before the hooks touch, its
  // largest the peak
  double root_strain = 0;
  for (const auto& row : rows) root_strain = std::max(root_strain, row.at("socket_corner_strain"));
  EXPECT_EQ(root_strain, hot["peak_strain"].get<double>());
  EXPECT_EQ(rows.front().at("socket_corner_strain"), 0);
  EXPECT_FALSE(hot.contains("plot"));                    // --no-render: no plots
  const double hook_z = socket["peak_von_mises_at"][2];  // where the socket starts
  EXPECT_LT(hook_z, -(2 - 0.2) * 0.0254);
  EXPECT_TRUE(socket["yield"]["exceeded_at"].is_number());
  // the +x paw's hook is pushed outward by the undercut (less the 0.002 in clearance)
  EXPECT_GT(widest, 0.9 * undercut);
  EXPECT_LT(widest, 1.1 * undercut);
  const auto& last = rows.back();
  EXPECT_LT(std::abs(last.at("hook_tip_ux")), 0.02 * undercut);  // snapped home
  EXPECT_NEAR(last.at("socket_z") - rows.front().at("socket_z"), -2.05 * 0.0254, 2e-4);
  EXPECT_NEAR(last.at("contact_force"), push, 0.01 * push);  // the base carries it
  EXPECT_NEAR(last.at("socket_rz"), -push, 0.01 * push);     // the grip passes it on
  // its contact cost step by step: the columns computed in the steps are all of them but the
  // floating frame's six modes; the most points are solved where the hooks pass under the
  // base part as the block lands on it
  const auto steps = read_history(out / "contact_steps.csv");
  ASSERT_EQ(static_cast<long>(steps.size()),
            summary["elastic_contact"]["steps_with_rows"].get<long>());
  long columns = 0;
  const std::map<std::string, double>* most = &steps.front();
  for (const auto& st : steps) {
    columns += static_cast<long>(st.at("new_columns"));
    if (st.at("points") > most->at("points")) most = &st;
  }
  EXPECT_EQ(columns + 6, summary["elastic_contact"]["response_solves"].get<long>());
  // the columns are those of the nodes the rows touched, the paws' and hooks' side of the
  // socket, not the block's far faces
  const long region = summary["elastic_contact"]["region_nodes"].get<long>(),
             surface = summary["elastic_contact"]["surface_nodes"].get<long>();
  EXPECT_GT(region, most->at("points"));
  EXPECT_LT(region, 0.8 * static_cast<double>(surface));
  // each node's columns solved once, when its first row came: never again as contact
  // spreads over the surface around it
  EXPECT_EQ(summary["elastic_contact"]["response_solves"].get<long>(), 3 * region + 6);
  EXPECT_EQ(most->at("points"), summary["elastic_contact"]["max_points"].get<double>());
  EXPECT_GT(most->at("t"), 0.08);
  EXPECT_LT(most->at("t"), 0.1);
  fs::remove_all(out);
}

// The snap-fit's socket driven down 0.4 in quasistatically (no slider, no push), at the
// default increments (a quarter of its 0.25 in mesh size: 1.13 mm of travel, halved where
// the contact rows do not settle) and at fine ones (0.071 mm). Where the hooks first meet the base
// part's edges, the lowest node of each lead face passes just outside the edge (the 0.001 in
// clearance), and the edge meets the face above it: the coarse increment gives the force and the
// hook's travel the fine ones give there (before, the node's row on the edge, whose normal is
// nearly vertical there, held the hooks up: 570 N and 0.06 mm instead of about 65 N and 1.0 mm).
// Both end sliding down the base part's sides on mu P_FE per paw, the hooks out by the undercut
// (the hook's probe 2.459 mm).
TEST(Cli, TheSnapFitSocketDrivenQuasistaticallyMeetsTheEdgesAtCoarseIncrements) {
  std::ifstream in(std::string(VPROTO_SAMPLES) + "/snapfit.vp");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto replace = [&](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
  };
  replace("joint slider socket axis=[0, 0, 1];", "move socket by=[0, 0, -0.4in] over=0.04s;");
  replace("force socket [0, 0, -push] ramp=0.05s;", "");
  replace("simulate(mode=dynamic, duration=0.4s, frames=60);",
          "simulate(mode=quasistatic, duration=0.04s, frames=10@DT@);");
  std::vector<std::map<std::string, double>> curves[2];
  for (const int fine : {0, 1}) {
    std::string script = text;
    script.replace(script.find("@DT@"), 4, fine ? ", dt=0.28ms" : "");
    const fs::path file = write_script(fine ? "socket_qs_fine.vp" : "socket_qs.vp", script);
    const fs::path out = fresh_dir(fine ? "socket_qs_fine" : "socket_qs");
    const Result r = run("run " + file.string() + " -o " + out.string() + " --no-render --quiet");
    ASSERT_EQ(r.code, 0) << r.output;
    curves[fine] = read_history(out / "history.csv");
    // every increment settles (the last cut, a 64th, passes up to 32 times: at 8 the
    // increment in which the apexes pass the edges was kept with 23.4 N, between the two
    // states its passes flipped between)
    const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
    EXPECT_EQ(summary["elastic_contact"]["unsettled_increments"], 0) << (fine ? "fine" : "coarse");
    fs::remove_all(out);
  }
  const auto& coarse = curves[0];
  const auto& fine = curves[1];
  // the default increments, and their halves where the hooks' apexes pass the edges
  ASSERT_LT(coarse.size(), 25u);
  ASSERT_GT(fine.size(), 100u);
  // the fine curve's column at the socket's height z, by linear interpolation
  auto fine_at = [&](double z, const char* column) {
    for (std::size_t k = 1; k < fine.size(); ++k) {
      const double z0 = fine[k - 1].at("socket_z"), z1 = fine[k].at("socket_z");
      if ((z0 - z) * (z1 - z) > 0) continue;
      const double w = (z - z0) / (z1 - z0);
      return (1 - w) * fine[k - 1].at(column) + w * fine[k].at(column);
    }
    return std::numeric_limits<double>::quiet_NaN();
  };
  // every coarse increment against the fine curve at the same travel: the hooks' deflection
  // to 1.5 % of the undercut, the force to 5 % of the fine curve's within 0.15 mm of travel
  // (after the apexes pass the edges it falls from 90 to 17 N within 0.4 mm, and with
  // friction the state follows the path: on the mesh of the canonically ordered CSG the
  // coarse increment at 59.65 mm, 0.28 mm after the one before, gave 74.5 N, the fine curve's
  // force 0.14 mm higher up; within 0.1 mm before).
  // Before the rows of features that left their triangles were dropped in every pass and
  // unsettled increments were cut: 146 N at 3.39 mm and 174 N at 4.52 mm against about 90 N,
  // the hooks 7 % too far out
  int compared = 0;
  for (const auto& row : coarse) {
    const double z = row.at("socket_z"), f = fine_at(z, "contact_force");
    if (!(f > 1.0)) continue;
    double lo = f, hi = f;
    for (const double dz : {-1.5e-4, -1e-4, -5e-5, 5e-5, 1e-4, 1.5e-4}) {
      const double g = fine_at(z + dz, "contact_force");
      if (std::isnan(g)) continue;  // (past the fine curve's end)
      lo = std::min(lo, g);
      hi = std::max(hi, g);
    }
    EXPECT_GT(row.at("contact_force"), 0.95 * lo) << "at z = " << z;
    EXPECT_LT(row.at("contact_force"), 1.05 * hi) << "at z = " << z;
    EXPECT_NEAR(row.at("hook_tip_ux"), fine_at(z, "hook_tip_ux"), 0.015 * 0.1 * 0.0254)
        << "at z = " << z;
    ++compared;
  }
  EXPECT_GE(compared, 10);
  // the first coarse increment with force, against the fine curve at the same travel
  const auto first = std::find_if(coarse.begin(), coarse.end(),
                                  [](const auto& row) { return row.at("contact_force") > 0; });
  ASSERT_NE(first, coarse.end());
  const double z = first->at("socket_z");
  double force = 0, hook = 0;
  for (std::size_t k = 1; k < fine.size(); ++k) {
    const double z0 = fine[k - 1].at("socket_z"), z1 = fine[k].at("socket_z");
    if ((z0 - z) * (z1 - z) > 0) continue;
    const double w = (z - z0) / (z1 - z0);
    force = (1 - w) * fine[k - 1].at("contact_force") + w * fine[k].at("contact_force");
    hook = (1 - w) * fine[k - 1].at("hook_tip_ux") + w * fine[k].at("hook_tip_ux");
    break;
  }
  ASSERT_GT(force, 30.0);  // riding over the edges there
  EXPECT_NEAR(first->at("contact_force"), force, 0.05 * force);
  EXPECT_NEAR(first->at("hook_tip_ux"), hook, 0.02 * hook);
  // sliding down the sides: the hooks as far out as the undercut puts them (the probe in
  // the hook's middle, the paw turning a little), the same at both increments
  const double undercut = 0.1 * 0.0254;
  EXPECT_GT(coarse.back().at("hook_tip_ux"), 0.95 * undercut);
  EXPECT_LT(coarse.back().at("hook_tip_ux"), undercut);
  EXPECT_NEAR(coarse.back().at("hook_tip_ux"), fine.back().at("hook_tip_ux"), 1e-4 * undercut);
  for (const auto* run : {&coarse, &fine}) {
    EXPECT_NEAR(run->back().at("contact_force"), 17.41, 0.01);  // mu P_FE for both paws
    // and from the first increment whose hooks are out by the undercut on: sliding
    bool out = false;
    for (const auto& row : *run) {
      out = out || row.at("hook_tip_ux") > 0.95 * undercut;
      if (out) {
        EXPECT_NEAR(row.at("contact_force"), 17.41, 0.01) << "at t = " << row.at("t");
      }
    }
    EXPECT_TRUE(out);
  }
}

TEST(Cli, RunTumblesAFreeBodyKeepingItsEnergy) {
  const fs::path out = fresh_dir("tumble");
  const Result r = run("run " + std::string(VPROTO_SAMPLES) + "/tumbling_t_handle.vp -o " +
                       out.string() + " --frames 5 --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto rows = read_history(out / "history.csv");
  ASSERT_GT(rows.size(), 7000u);
  const double e0 = rows.front().at("kinetic_energy");
  double worst = 0;
  for (const auto& row : rows)
    worst = std::max(worst, std::abs(row.at("kinetic_energy") - e0) / e0);
  EXPECT_LT(worst, 1e-9);
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto q = summary["bodies"][0]["rotation"];
  double norm = 0;
  for (const auto& c : q) norm += c.get<double>() * c.get<double>();
  EXPECT_NEAR(norm, 1.0, 1e-12);
  fs::remove_all(out);
}

TEST(Cli, RunFollowsAProjectileThatLandsRigidOrElastic) {
  // a ball thrown sideways over a fixed floor: free flight is exact, the landing is a
  // contact event at the instant the ball reaches the floor
  const std::string scene =
      "rigid body floor (material=steel) { translate([-5, -1, -0.1]) box([10, 2, 0.1]); }\n"
      "BALL body ball (material=steel) { translate([0, 0, 1]) sphere(r=0.05, segments=16); }\n"
      "fix floor;\ngravity [0, 0, -9.81];\nvelocity ball linear=[2, 0, 0];\n"
      "probe c ball point=[0, 0, 1];\n"
      "simulate(duration=0.3s, dt=1ms, frames=4);\nrender(size=[160, 120]);\n";
  auto with = [&](const std::string& kind) {
    std::string s = scene;
    s.replace(s.find("BALL"), 4, kind);
    return s;
  };
  const fs::path script = write_script("vproto_cli_throw.vp", with("rigid"));
  const fs::path out = fresh_dir("throw");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto u = summary["probes"]["c"]["u"];
  EXPECT_NEAR(u[0].get<double>(), 2 * 0.3, 1e-12);
  EXPECT_NEAR(u[2].get<double>(), -0.5 * 9.81 * 0.3 * 0.3, 1e-12);
  // energy: kinetic gained = work done by gravity
  const double mass = nlohmann::json::parse(std::ifstream(out / "build.json"))["bodies"][1]["mass"];
  const double kinetic = 0.5 * mass * (2 * 2 + std::pow(9.81 * 0.3, 2));
  EXPECT_NEAR(summary["energy"]["kinetic"].get<double>(), kinetic, 1e-12 * kinetic);
  EXPECT_NEAR(summary["energy"]["external_work"].get<double>(), kinetic - 0.5 * mass * 4,
              1e-9 * kinetic);
  // nothing is lost in free flight: the starting kinetic energy counts (issue 13)
  EXPECT_NEAR(summary["energy"]["dissipated"].get<double>(), 0, 1e-9 * kinetic);
  EXPECT_TRUE(summary["events"].empty());
  // a longer run lands: the lowest vertex (0.95 m up) meets the floor at sqrt(2 h / g)
  const fs::path out2 = fresh_dir("throw2");
  const Result r2 =
      run("run " + script.string() + " -o " + out2.string() + " --duration 1s --frames 20 --quiet");
  ASSERT_EQ(r2.code, 0) << r2.output;
  const auto landed = nlohmann::json::parse(std::ifstream(out2 / "summary.json"));
  ASSERT_FALSE(landed["events"].empty()) << landed.dump(2);
  // 1 ms does not divide the frame interval (1/19 s): the step used says so (issue 13)
  EXPECT_EQ(landed["time_step_requested"].get<double>(), 1e-3);
  EXPECT_NEAR(landed["time_step"].get<double>(), (1.0 / 19) / 53, 1e-15);
  EXPECT_NE(landed["time_step_reason"].get<std::string>().find("cut to divide the frame"),
            std::string::npos);
  const auto& first = landed["events"][0];
  EXPECT_EQ(first["type"], "contact_added");
  EXPECT_EQ(first["bodies"], nlohmann::json::array({"floor", "ball"}));
  // (the 16-segment sphere's lowest vertex is a little above 0.95 m: within 1 mm)
  EXPECT_NEAR(first["t"].get<double>(), std::sqrt(2 * 0.95 / 9.81), 3e-4);
  EXPECT_GT(landed["peak_contact_force"].get<double>(), mass * 9.81);
  EXPECT_LT(landed["contact"]["max_penetration"].get<double>(), 1e-6);
  const double z = landed["bodies"][1]["position"][2];
  EXPECT_GT(z, 0.045);  // on the floor, not in it
  EXPECT_LT(z, 0.06);
  // the history's contact columns follow the landing
  std::ifstream history(out2 / "history.csv");
  std::string line, last;
  std::getline(history, line);
  EXPECT_EQ(line.rfind("t,step,contacts,contact_force,", 0), 0u);
  while (std::getline(history, line)) last = line;
  EXPECT_NE(last.substr(last.find(',', last.find(',') + 1) + 1, 2), "0,") << last;

  // the same ball elastic: nothing holds it, so it floats (its frame carries the inertia,
  // no FE work until it touches) and lands at the same instant; it is no holder's load,
  // so history.csv has no reaction columns for it
  std::string soft_scene = with("elastic");
  const std::string ball_head = "ball (material=steel)";
  soft_scene.replace(soft_scene.find(ball_head), ball_head.size(),
                     "ball (material=steel, mesh_size=0.025, element=tet4)");
  const fs::path elastic = write_script("vproto_cli_throw_elastic.vp", soft_scene);
  const fs::path out3 = fresh_dir("throw3");
  const Result r3 = run("run " + elastic.string() + " -o " + out3.string() +
                        " --duration 1s --frames 20 --quiet");
  ASSERT_EQ(r3.code, 0) << r3.output;
  const auto soft = nlohmann::json::parse(std::ifstream(out3 / "summary.json"));
  ASSERT_FALSE(soft["events"].empty()) << soft.dump(2);
  EXPECT_EQ(soft["events"][0]["type"], "contact_added");
  EXPECT_NEAR(soft["events"][0]["t"].get<double>(), first["t"].get<double>(), 2e-3);
  EXPECT_GT(soft["elastic_contact"]["rigid_only_steps"].get<long>(), 0);
  EXPECT_GE(soft["energy"]["dissipated"].get<double>(), 0);
  const double zs = soft["bodies"][1]["position"][2];
  EXPECT_GT(zs, 0.04);  // on the floor, not in it
  EXPECT_LT(zs, 0.06);
  std::ifstream soft_history(out3 / "history.csv");
  std::getline(soft_history, line);
  EXPECT_EQ(line.find("ball_rx"), std::string::npos) << line;
  fs::remove_all(out);
  fs::remove_all(out2);
  fs::remove_all(out3);
}

}  // namespace

namespace {

TEST(Cli, InclineSampleSlidesOrSticksAsCoulombSays) {
  const fs::path script = fs::path(VPROTO_SAMPLES) / "incline.vp";
  const fs::path out = fresh_dir("incline");
  const Result r =
      run("run " + script.string() + " -o " + out.string() + " --no-render --frames 3 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto slid = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  // the block's corner travels a t^2 / 2 down the slope in 1 s, a = g (sin 30 - 0.3 cos 30)
  const auto u = slid["probes"]["corner"]["u"];
  const double a = 9.81 * (0.5 - 0.3 * std::sqrt(3.0) / 2);
  EXPECT_NEAR(std::hypot(u[0].get<double>(), u[2].get<double>()), a / 2, 0.01 * a / 2);
  ASSERT_EQ(slid["events"].size(), 1u);  // touching from the start to the end
  EXPECT_EQ(slid["events"][0]["type"], "contact_added");
  // with mu above tan 30 it stays
  const fs::path out2 = fresh_dir("incline_stick");
  const Result r2 = run("run " + script.string() + " -o " + out2.string() +
                        " --no-render --frames 3 --quiet --set mu=0.7");
  ASSERT_EQ(r2.code, 0) << r2.output;
  const auto held = nlohmann::json::parse(std::ifstream(out2 / "summary.json"));
  const auto u2 = held["probes"]["corner"]["u"];
  EXPECT_LT(std::hypot(u2[0].get<double>(), u2[1].get<double>(), u2[2].get<double>()), 1e-6);
  EXPECT_LT(held["contact"]["max_penetration"].get<double>(), 1e-6);
  fs::remove_all(out);
  fs::remove_all(out2);
}

TEST(Cli, BenchQuickMeasuresWorkAgainstPrecision) {
  const fs::path out = fresh_dir("bench");
  const Result r = run("bench --quick -o " + out.string() + " --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto doc = nlohmann::json::parse(std::ifstream(out / "bench.json"));
  EXPECT_LT(doc["csg"]["volume_relative_error"].get<double>(), 1e-9);
  // the holes' segments: the plate's volume error is exactly the N-gons' faceting error
  ASSERT_GE(doc["csg"]["segments_sweep"].size(), 3u);
  for (const auto& row : doc["csg"]["segments_sweep"]) {
    const double n = row["segments"].get<double>(), r2 = 0.004 * 0.004, pi = std::acos(-1.0);
    const double round = 0.1 * 0.1 * 0.01 - 49 * 0.01 * pi * r2;
    const double faceting = 49 * 0.01 * (pi * r2 - 0.5 * n * r2 * std::sin(2 * pi / n)) / round;
    EXPECT_NEAR(row["volume_relative_error"].get<double>(), faceting, 1e-9 * faceting) << row;
  }
  // the report: one log-log plot per family, each on the page, with the machine and commit
  ASSERT_TRUE(fs::exists(out / "report.html"));
  ASSERT_TRUE(fs::exists(out / "report.md"));
  std::stringstream page;
  page << std::ifstream(out / "report.html").rdbuf();
  for (const char* family : {"csg", "fe_static", "fe_frequency", "newmark", "newmark_tolerance",
                             "paw", "rigid", "pendulum", "contact"}) {
    const std::string plot = std::string("plots/") + family + ".png";
    EXPECT_TRUE(fs::exists(out / plot)) << plot;
    EXPECT_NE(page.str().find("<img src=\"" + plot + "\""), std::string::npos) << plot;
  }
  // CalculiX, where installed, on the very same meshes: the same displacements and
  // frequencies to its printed digits; else the report says how to install it
  if (std::system("command -v ccx > /dev/null 2>&1") == 0) {
    for (const auto& row : doc["elastic"]["static_cantilever"])
      EXPECT_LT(row["calculix"]["max_relative_difference"].get<double>(), 1e-6) << row;
    for (const auto& row : doc["elastic"]["first_frequency"])
      EXPECT_LT(std::abs(row["calculix"]["relative_difference"].get<double>()), 1e-6) << row;
    EXPECT_NE(page.str().find("CalculiX (ccx, 2 threads) on the very meshes"), std::string::npos);
  } else {
    EXPECT_NE(page.str().find("apt-get install calculix-ccx"), std::string::npos);
  }
  // the plate in Manifold, where installed, is the same polyhedron
  const auto& manifold = doc["csg"]["peers"]["manifold"];
  if (manifold.contains("seconds"))
    EXPECT_LT(manifold["volume_relative_error"].get<double>(), 1e-9) << manifold;
  else
    EXPECT_NE(manifold["skipped"].get<std::string>().find("npm install -g manifold-3d"),
              std::string::npos)
        << manifold;
  EXPECT_TRUE(doc["csg"]["peers"]["openscad"].contains("skipped"));  // the full sweep's
  // the pendulum's period converges at second order on the large-amplitude value
  const auto& pendulum = doc["pendulum"];
  ASSERT_GE(pendulum.size(), 3u);
  for (std::size_t i = 0; i + 1 < pendulum.size(); ++i) {
    const double ratio =
        pendulum[i]["period_error"].get<double>() / pendulum[i + 1]["period_error"].get<double>();
    EXPECT_GT(ratio, 3.5) << pendulum[i];
    EXPECT_LT(ratio, 4.5) << pendulum[i];
  }
  EXPECT_LT(std::abs(pendulum.back()["period_error"].get<double>()), 1e-4);
  EXPECT_LT(pendulum.back()["energy_drift"].get<double>(), 1e-4);
  // each skip measured with and without, the answer the same either way
  std::set<std::string> skips;
  for (const auto& row : doc["skips"]) {
    EXPECT_TRUE(row["same_result"].get<bool>()) << row;
    skips.insert(row["skip"].get<std::string>());
  }
  for (const char* skip :
       {"CSG: bounding boxes, one batched difference",
        "convex parts only for bodies that can touch", "compile cache after --set",
        "no rendering with --no-render", "no mesh for elastic bodies nothing loads",
        "one factorization per run", "islands", "rigid until contact"})
    EXPECT_EQ(skips.count(skip), 1u) << skip;
  EXPECT_NE(page.str().find("Skips, measured"), std::string::npos);
  EXPECT_GT(doc["machine"]["cores"].get<int>(), 0);
  EXPECT_NE(page.str().find(doc["commit"].get<std::string>()), std::string::npos);
  ASSERT_EQ(doc["render"].size(), 2u);
  EXPECT_GT(doc["render"][1]["triangles"].get<double>(), 90000);
  // the rotation integrator is second order: halving dt quarters the error
  const auto& rigid = doc["rigid"];
  ASSERT_GE(rigid.size(), 3u);
  for (std::size_t i = 0; i + 1 < rigid.size(); ++i) {
    const double ratio =
        rigid[i]["omega_error"].get<double>() / rigid[i + 1]["omega_error"].get<double>();
    EXPECT_GT(ratio, 3.5);
    EXPECT_LT(ratio, 4.5);
    EXPECT_LT(rigid[i]["energy_drift"].get<double>(), 1e-10);
  }
  // elastic: tet10 converges on CalculiX, tet4 locks; Newmark's period error is (wh)^2/12
  const auto& elastic = doc["elastic"];
  for (const auto& row : elastic["static_cantilever"]) {
    const double err = row["tip_relative_error"].get<double>();
    if (row["element"] == "tet10")
      EXPECT_LT(std::abs(err), 0.005) << row;
    else
      EXPECT_LT(err, -0.02) << row;
  }
  for (const auto& row : elastic["newmark"]) {
    const double predicted = row["predicted_period_error"].get<double>();
    EXPECT_NEAR(row["period_error"].get<double>(), predicted, 0.05 * predicted) << row;
    EXPECT_LT(row["energy_fluctuation"].get<double>(), 1e-9) << row;
  }
  // the snap-fit paw: the sliding force within 0.5 % of CalculiX on the same mesh (the
  // issue asks 2 %), and converging with h on CalculiX's finest
  EXPECT_EQ(doc["paw"]["reference"].get<std::string>().find("not found"), std::string::npos);
  const auto& paw = doc["paw"]["mesh_sweep"];
  ASSERT_GE(paw.size(), 2u) << doc["paw"];
  // (where CalculiX's run reached the slide: at 0.07 in with friction it stopped converging
  // at the apex, 6.97 mm, on the meshes of 2026-11-28, and the row has no difference)
  int compared = 0;
  for (const auto& row : paw)
    if (row.contains("sliding_difference")) {
      EXPECT_LT(std::abs(row["sliding_difference"].get<double>()), 0.005) << row;
      ++compared;
    }
  EXPECT_GE(compared, 1) << doc["paw"];
  for (std::size_t i = 0; i + 1 < paw.size(); ++i)
    EXPECT_LT(std::abs(paw[i + 1]["sliding_error_vs_calculix_0.05in"].get<double>()),
              std::abs(paw[i]["sliding_error_vs_calculix_0.05in"].get<double>()))
        << paw[i + 1];
  // and the push as the lead face rides over the edge (0.26 in of travel) within 2 % of
  // CalculiX's at every increment swept, 0.025 in the coarsest: the catch's edge rows are
  // taken anew where each increment ends them (with the planes they had at its start:
  // -5.1 %, +1.7 %, -2.4 % at 0.025, 0.0125, 0.00625 in). (+1.7 % at 0.025 in: the
  // increment that holds the apex's passing is halved, and the normals of its first half
  // follow the turn of the whole increment before it; +0.3 % and +0.9 % at the others.)
  // The peak, just before the apex passes the edge, is the same at every increment to 1 %:
  // an increment in which the push lets go is halved until the release is found (8.14,
  // 8.41, 8.18 N before, against 8.02 N converged)
  const auto& sweep = doc["paw"]["increment_sweep"];
  ASSERT_GE(sweep.size(), 3u);
  // every increment of every row settles (some are halved where the apex passes the edge)
  for (const auto* rows : {&paw, &sweep})
    for (const auto& row : *rows) {
      EXPECT_EQ(row["unsettled_increments"].get<long>(), 0) << row;
      EXPECT_GT(row["cut_increments"].get<long>(), 0) << row;
    }
  const double finest_peak = sweep.back()["peak_push_N"].get<double>();
  for (const auto& row : sweep) {
    EXPECT_LT(std::abs(row["push_difference"].get<double>()), 0.02) << row;
    EXPECT_NEAR(row["peak_push_N"].get<double>(), finest_peak, 0.01 * finest_peak) << row;
  }
  // the tolerance= knob through the engine's own step rule: the period error it asks for
  ASSERT_GE(elastic["newmark_tolerance"].size(), 3u);
  for (const auto& row : elastic["newmark_tolerance"]) {
    const double tolerance = row["tolerance"].get<double>(),
                 err = row["period_error"].get<double>();
    EXPECT_GT(err, 0.9 * tolerance) << row;  // the step is not smaller than it need be
    EXPECT_LE(err, tolerance) << row;
    EXPECT_LT(row["energy_error"].get<double>(), 1e-8) << row;
  }
  EXPECT_LT(
      std::abs(
          elastic["first_frequency"].back()["relative_error_vs_euler_bernoulli"].get<double>()),
      0.005);
  fs::remove_all(out);
  // contact: the judged cases within their targets, piles settled without interpenetrating
  const auto& contact = doc["contact"];
  for (const auto& b : contact["bounce"]) {
    EXPECT_LT(std::abs(b["rebound_relative_error"].get<double>()), 0.01) << b;
    EXPECT_LT(b["max_penetration"].get<double>(), 1e-6) << b;
  }
  EXPECT_LT(std::abs(contact["incline_slide"]["relative_error"].get<double>()), 0.01);
  EXPECT_LT(contact["incline_stick"]["drift_over_1s"].get<double>(), 1e-6);
  EXPECT_LT(contact["stack_of_five"]["creep"].get<double>(), 1e-6);
  EXPECT_LT(contact["stack_of_five"]["max_penetration"].get<double>(), 1e-6);
  for (const auto& p : contact["pile"]) EXPECT_LT(p["max_penetration"].get<double>(), 1e-4) << p;
  // a free soft slab landing flat: no force beyond its impact's, flat and on the plate
  ASSERT_FALSE(contact["soft_slab_lands_flat"].empty());
  for (const auto& l : contact["soft_slab_lands_flat"]) {
    EXPECT_LT(l["peak_over_impact"].get<double>(), 1.5) << l;
    EXPECT_LT(l["final_tilt"].get<double>(), 1e-5) << l;
    EXPECT_LT(l["centre_height_error"].get<double>(), 1e-6) << l;
    // and it comes to rest: at least 100 of the 250 steps skipped (140 found; 49 while the
    // contact stage turned the normals of its settling rows each step)
    EXPECT_GE(l["resting_steps"].get<double>(), 100) << l;
  }
  // a steel block held, then pushed along, on a rubber pad: still while held (1e-7 J when
  // its steps ended at g dt / 2), and sliding at its speed (half a step's friction fast)
  const auto& held = contact["held_on_rubber"];
  EXPECT_LT(held["held_kinetic_energy"].get<double>(), 1e-10) << held;
  EXPECT_LT(std::abs(held["sliding_speed_error"].get<double>()), 5e-4) << held;
}

}  // namespace

namespace {

TEST(Cli, BuildTetsWritesElasticBodiesAsVtu) {
  const fs::path script =
      write_script("vproto_cli_tets.vp",
                   "elastic body beam (material=steel, mesh_size=0.01, element=tet10) {\n"
                   "  box([0.3, 0.05, 0.05]);\n}\n"
                   "rigid body block (material=steel) { translate([1, 0, 0]) box(0.1); }\n");
  const fs::path out = fresh_dir("tets");
  const Result r = run("build " + script.string() + " -o " + out.string() + " --tets --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto doc = nlohmann::json::parse(std::ifstream(out / "build.json"));
  const auto& beam = doc["bodies"][0];
  EXPECT_GT(beam["tets"].get<int>(), 100);
  EXPECT_EQ(beam["tet_mesh"]["element"], "tet10");
  EXPECT_NEAR(beam["tet_mesh"]["mesh_volume"].get<double>(), 0.3 * 0.05 * 0.05, 1e-12);
  EXPECT_GT(beam["tet_mesh"]["min_tet_volume"].get<double>(), 0);
  EXPECT_EQ(doc["bodies"][1]["tets"], 0);  // rigid bodies are never meshed
  EXPECT_FALSE(fs::exists(out / "block.vtu"));
  std::ifstream vtu(out / "beam.vtu");
  std::string text((std::istreambuf_iterator<char>(vtu)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("NumberOfPoints=\"" + std::to_string(beam["nodes"].get<int>()) + "\""),
            std::string::npos);
  EXPECT_NE(text.find("NumberOfCells=\"" + std::to_string(beam["tets"].get<int>()) + "\""),
            std::string::npos);
  EXPECT_NE(text.find("\n24\n"), std::string::npos);  // VTK_QUADRATIC_TETRA
  // a mesh size the body cannot take: exit 2, naming the body, nothing written
  const fs::path thin =
      write_script("vproto_cli_thin.vp",
                   "elastic body sheet (material=steel, mesh_size=0.05) { box([1, 1, 0.01]); }\n");
  const fs::path out2 = fresh_dir("thin");
  const Result t = run("build " + thin.string() + " -o " + out2.string() + " --tets");
  EXPECT_EQ(t.code, 2);
  EXPECT_NE(t.output.find("body 'sheet': the body is too thin"), std::string::npos) << t.output;
  EXPECT_FALSE(fs::exists(out2));
  fs::remove_all(out);
}

}  // namespace

namespace {

TEST(Cli, StaticRunOfTheCantileverMatchesCalculix) {
  const fs::path out = fresh_dir("cantilever");
  const Result r = run("run " + std::string(VPROTO_SAMPLES) + "/cantilever.vp -o " + out.string() +
                       " --set size=20mm --frames 3 --size 320x180 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["mode"], "static");
  const double tip = -summary["probes"]["tip"]["u"][2].get<double>();
  EXPECT_NEAR(tip, 3.043e-4, 0.003 * 3.043e-4);  // CalculiX C3D10 (references.md)
  const double strain = summary["energy"]["strain"], work = summary["energy"]["external_work"];
  EXPECT_NEAR(strain, 0.5 * work, 1e-9 * work);  // Clapeyron: U = W / 2 at equilibrium
  EXPECT_NEAR(work, 100 * tip, 0.01 * work);     // W = F times the mean end deflection
  EXPECT_GT(summary["bodies"][0]["max_von_mises"].get<double>(), 1e6);
  // the clamp carries the load
  EXPECT_NEAR(summary["bodies"][0]["reaction"][2].get<double>(), 100.0, 1e-6);
  EXPECT_NEAR(summary["bodies"][0]["reaction"][0].get<double>(), 0.0, 1e-6);
  EXPECT_TRUE(fs::exists(out / "meshes" / "beam_0002.vtu"));
  EXPECT_TRUE(fs::exists(out / "meshes" / "series.pvd"));
  std::ifstream vtu(out / "meshes" / "beam_0002.vtu");
  const std::string text((std::istreambuf_iterator<char>(vtu)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("Name=\"displacement\" NumberOfComponents=\"3\" format=\"appended\""),
            std::string::npos);
  EXPECT_NE(text.find("Name=\"von_mises\""), std::string::npos);
  EXPECT_NE(text.find("Name=\"strain\""), std::string::npos);
  EXPECT_NE(text.find("<AppendedData encoding=\"raw\">"), std::string::npos);
  EXPECT_TRUE(fs::exists(out / "frames" / "frame_0002.png"));
  // every stage of the static run is timed (issue 11: they were 0)
  for (const char* stage : {"mesh", "assemble", "factor", "solve", "stresses", "export"})
    EXPECT_GT(summary["wall_time"][stage].get<double>(), 0) << stage;
  fs::remove_all(out);
}

// A mesh whose factor would not fit in memory is refused before any numeric work, naming
// the body and the mesh size that fits (issue 13: exit 1, "CHOLMOD analysis failed"); the
// limit is the memory available, or VPROTO_MEMORY_LIMIT, set low here.
TEST(Cli, AFactorThatWouldNotFitIsRefusedWithTheMeshSizeThatFits) {
  const fs::path out = fresh_dir("memory");
  for (const char* mode : {"static", "dynamic"}) {
    const Result r =
        run("run " + std::string(VPROTO_SAMPLES) + "/cantilever.vp -o " + out.string() +
            " --set size=20mm --mode " + mode +
            " --duration 1ms --frames 2 --no-render; VPROTO_MEMORY_LIMIT=2MB " + VPROTO_EXE +
            " run " + VPROTO_SAMPLES + "/cantilever.vp -o " + out.string() +
            "_low --set size=20mm --mode " + mode + " --duration 1ms --frames 2 --no-render");
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find("error: body 'beam' (mesh_size 0.02 m"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("use a mesh_size of at least"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out.string() + "_low"));
    // (the same run with the machine's memory went through)
    EXPECT_TRUE(fs::exists(out / "summary.json")) << r.output;
    fs::remove_all(out);
  }
}

// A contact problem too large for the memory left stops the run with exit 3 before its
// allocation, naming the body, the time and the fix, with what was simulated until then
// written (an annular snap-fit's lip pressed all round its bead, 7,270 points, was killed by
// the system at 24 GB with nothing said). The limit is VPROTO_MEMORY_LIMIT, set here where
// the pad's factor (6,042 unknowns, about 10 MB by the estimate the backend's choice takes)
// fits and the compliance columns of its 500 pressed nodes (each at all of them: 18.0 MB,
// and 1.2 MB for the solve of 16 of them at a time) do not.
TEST(Cli, AContactProblemThatWouldNotFitStopsTheRunNamingTheBody) {
  const fs::path script = write_script(
      "vproto_cli_press_memory.vp",
      "units length=mm;\n"
      "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; }\n"
      "elastic body pad (material=rubber, mesh_size=5mm, element=tet4) {\n"
      "  translate([-60, -60, -5]) box([120, 120, 5]);\n}\n"
      "rigid body press (material=steel) { translate([-55, -55, 0.5]) box([110, 110, 10]); }\n"
      "fix pad region=box([-61, -61, -5.1], [61, 61, -4.9]);\n"
      "move press by=[0, 0, -1.5] over=0.1s;\n"
      "contact pad press friction=0.5;\n"
      "simulate(mode=quasistatic, duration=0.1s, frames=3);\n");
  const fs::path out = fresh_dir("contact_memory");
  const Result low = shell("VPROTO_MEMORY_LIMIT=12MB " + std::string(VPROTO_EXE) + " run " +
                           script.string() + " -o " + out.string() + " --no-render --quiet");
  EXPECT_EQ(low.code, 3) << low.output;
  EXPECT_NE(low.output.find("contact of 'pad' at t = 0 s: the compliance columns of its 500 "
                            "contact nodes need 19.2 MB, more than the 12 MB of memory left"),
            std::string::npos)
      << low.output;
  EXPECT_NE(low.output.find("give 'pad' a coarser mesh_size where it touches (now 0.005 m"),
            std::string::npos)
      << low.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["status"], "failed");
  EXPECT_TRUE(fs::exists(out / "history.csv"));
  // the same run with the machine's memory goes through
  const Result full =
      run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  EXPECT_EQ(full.code, 0) << full.output;
  fs::remove_all(out);
}

// Under their memory bound (a third of the memory left), the compliance columns of the
// nodes that rows needed longest ago go first, and the points about to close take none
// along when the rows' own leave no room for them: a dome pressed into a pad and slid
// along it leaves the nodes behind it, so with the bound the run solves few more columns
// than without it (1,128 against 1,059; dropping them all, as until 2026-11-27, solved
// 2,997), and the forces are the same to rounding.
TEST(Cli, ColumnsPastTheirMemoryBoundDropThoseLeastRecentlyNeeded) {
  const fs::path script =
      write_script("vproto_cli_slide_memory.vp",
                   "units length=mm;\n"
                   "material rubber { E = 10MPa; nu = 0.45; density = 1100kg/m^3; }\n"
                   "elastic body pad (material=rubber, mesh_size=5mm, element=tet4) {\n"
                   "  translate([-80, -30, -10]) box([160, 60, 10]);\n}\n"
                   "rigid body dome (material=steel) {\n"
                   "  translate([-50, 0, 300.5]) sphere(r=300, segments=48);\n}\n"
                   "fix pad region=box([-81, -31, -10.1], [81, 31, -9.9]);\n"
                   "move dome by=[0, 0, -2] over=0.02s;\n"
                   "move dome by=[100, 0, 0] over=0.1s;\n"
                   "contact pad dome friction=0.3;\n"
                   "simulate(mode=quasistatic, duration=0.12s, frames=6);\n");
  const fs::path free = fresh_dir("slide_memory_free"), bound = fresh_dir("slide_memory_bound");
  const Result a = run("run " + script.string() + " -o " + free.string() + " --no-render --quiet");
  ASSERT_EQ(a.code, 0) << a.output;
  const Result b = shell("VPROTO_MEMORY_LIMIT=4MB " + std::string(VPROTO_EXE) + " run " +
                         script.string() + " -o " + bound.string() + " --no-render --quiet");
  ASSERT_EQ(b.code, 0) << b.output;
  const auto sa = nlohmann::json::parse(std::ifstream(free / "summary.json"));
  const auto sb = nlohmann::json::parse(std::ifstream(bound / "summary.json"));
  const auto& ea = sa["elastic_contact"];
  const auto& eb = sb["elastic_contact"];
  EXPECT_EQ(ea["column_drops"].get<long>(), 0);
  EXPECT_GE(eb["column_drops"].get<long>(), 1);
  // (nodes with columns at the end: fewer kept)
  EXPECT_LT(eb["region_nodes"].get<long>(), ea["region_nodes"].get<long>());
  // (1,128 against 1,059: a few nodes taken along for points about to close go before
  // those points close)
  EXPECT_LT(eb["response_solves"].get<double>(), 1.25 * ea["response_solves"].get<double>());
  ASSERT_EQ(sa["bodies"][0]["name"], "pad");
  const auto& ra = sa["bodies"][0]["reaction"];
  const auto& rb = sb["bodies"][0]["reaction"];
  double size = 0, apart = 0;
  for (int k = 0; k < 3; ++k) {
    size = std::max(size, std::abs(ra[k].get<double>()));
    apart = std::max(apart, std::abs(ra[k].get<double>() - rb[k].get<double>()));
  }
  EXPECT_GT(size, 3000.0);  // (the dome pressed and dragged: 3.9 kN and 1.2 kN)
  EXPECT_LT(apart, 1e-9 * size);
  fs::remove_all(free);
  fs::remove_all(bound);
}

TEST(Cli, StaticRunRefusesWhatHasNoEquilibrium) {
  const fs::path out = fresh_dir("nostatic");
  const fs::path free_body = write_script(
      "vproto_cli_free.vp",
      "elastic body plate (material=aluminum, mesh_size=0.02) { box([0.2, 0.1, 0.05]); }\n"
      "force plate [0, 0, -10];\nsimulate(mode=static);\n");
  const Result a = run("run " + free_body.string() + " -o " + out.string());
  EXPECT_EQ(a.code, 2);
  EXPECT_NE(a.output.find("vproto_cli_free.vp:1:1: error: elastic body 'plate' is held by nothing"),
            std::string::npos)
      << a.output;
  EXPECT_FALSE(fs::exists(out));
  const fs::path rubber =
      write_script("vproto_cli_rubber.vp",
                   "material goo { E = 1MPa; nu = 0.499; density = 1000; }\n"
                   "elastic body b (material=goo, mesh_size=0.02) { box([0.2, 0.1, 0.05]); }\n"
                   "fix b region=box([-1, -1, -1], [0.001, 1, 1]);\nsimulate(mode=static);\n");
  const Result b = run("run " + rubber.string() + " -o " + out.string());
  EXPECT_EQ(b.code, 2);
  EXPECT_NE(b.output.find("too close to 0.5"), std::string::npos) << b.output;
  // a free rigid body under gravity has no static equilibrium (issue 13: it was "ok")
  const fs::path falling =
      write_script("vproto_cli_falling.vp",
                   "elastic body b (material=steel, mesh_size=0.02) { box([0.2, 0.1, 0.05]); }\n"
                   "rigid body r (material=steel) { translate([0, 0, 1]) box(0.1); }\n"
                   "fix b region=box([-1, -1, -1], [0.001, 1, 1]);\ngravity [0, 0, -9.81];\n"
                   "simulate(mode=static);\n");
  const Result g = run("run " + falling.string() + " -o " + out.string());
  EXPECT_EQ(g.code, 2);
  EXPECT_NE(g.output.find("vproto_cli_falling.vp:2:1: error: body 'r' is rigid and free, and "
                          "gravity pulls it"),
            std::string::npos)
      << g.output;
  EXPECT_FALSE(fs::exists(out));
  const fs::path empty_region =
      write_script("vproto_cli_region.vp",
                   "elastic body b (material=steel, mesh_size=0.02) { box([0.2, 0.1, 0.05]); }\n"
                   "fix b region=box([5, 5, 5], [6, 6, 6]);\nsimulate(mode=static);\n");
  const Result c = run("run " + empty_region.string() + " -o " + out.string() + " --no-render");
  EXPECT_EQ(c.code, 2);
  EXPECT_NE(
      c.output.find("vproto_cli_region.vp:2:1: error: fix region selects no node of body 'b'"),
      std::string::npos)
      << c.output;
  fs::remove_all(out);
}

TEST(Cli, DynamicRunOfTheCantileverVibratesAtItsFirstFrequency) {
  const fs::path out = fresh_dir("vibration");
  const Result r = run("run " + std::string(VPROTO_SAMPLES) + "/cantilever_vibration.vp -o " +
                       out.string() + " --set size=25mm --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["mode"], "dynamic");
  EXPECT_EQ(summary["solver"]["beam"]["factorizations"], 1);  // one factor for every step
  const auto rows = read_history(out / "history.csv");
  ASSERT_GT(rows.size(), 150u);
  // a sudden tip load: the tip swings between 0 and twice the static deflection, about
  // which it crosses at the first bending frequency
  const double static_tip = -3.043e-4;
  double lowest = 0, worst_balance = 0, work = 0;
  std::vector<double> crossings;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const double z0 = rows[i - 1].at("tip_uz"), z1 = rows[i].at("tip_uz");
    lowest = std::min(lowest, z1);
    if (z0 > static_tip && z1 <= static_tip)
      crossings.push_back(rows[i - 1].at("t") +
                          (rows[i].at("t") - rows[i - 1].at("t")) * (z0 - static_tip) / (z0 - z1));
    work = rows[i].at("external_work");
    worst_balance = std::max(
        worst_balance, std::abs(rows[i].at("kinetic_energy") + rows[i].at("strain_energy") - work));
  }
  EXPECT_NEAR(lowest, 2 * static_tip, 0.05 * 2 * -static_tip);
  ASSERT_GE(crossings.size(), 3u);
  const double f = (crossings.size() - 1) / (crossings.back() - crossings.front());
  EXPECT_NEAR(f, 41.78, 0.01 * 41.78);    // Euler-Bernoulli f1 (references.md)
  EXPECT_LT(worst_balance, 1e-9 * work);  // kinetic + strain = work done, undamped
  EXPECT_TRUE(fs::exists(out / "meshes" / "beam_0050.vtu"));
  EXPECT_TRUE(fs::exists(out / "meshes" / "series.pvd"));
  fs::remove_all(out);
}

TEST(Cli, DampedDynamicRunSettlesOnTheStaticDeflection) {
  const fs::path script =
      write_script("vproto_cli_damped.vp",
                   "units length=mm force=N;\n"
                   "elastic body beam (material=steel, mesh_size=25mm) { box([1000, 50, 50]); }\n"
                   "fix beam region=box([-1, -1, -1], [0.001, 51, 51]);\n"
                   "force beam [0, 0, -100] region=box([999.999, -1, -1], [1001, 51, 51]);\n"
                   "probe tip beam point=[1000, 25, 25];\n"
                   "simulate(mode=dynamic, duration=0.3s, dt=1ms, frames=4, mass_damping=263/1s,\n"
                   "         stiffness_damping=1e-4s);\n");
  const fs::path out = fresh_dir("damped");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const double tip = -summary["probes"]["tip"]["u"][2].get<double>();
  EXPECT_NEAR(tip, 3.043e-4, 0.01 * 3.043e-4);  // at rest on the static deflection
  const auto& energy = summary["energy"];
  // the load did work 100 N x tip; half of it is stored, half was damped out
  EXPECT_NEAR(energy["dissipated"].get<double>(), energy["strain"].get<double>(),
              0.02 * energy["strain"].get<double>());
  EXPECT_NEAR(summary["bodies"][0]["reaction"][2].get<double>(), 100.0, 1.0);
  fs::remove_all(out);
}

TEST(Cli, DynamicRunMovesAGripAndReportsItsReaction) {
  // a plate gripped at one end is carried 10 mm sideways by its frame
  const fs::path script =
      write_script("vproto_cli_grip.vp",
                   "units length=mm force=N;\n"
                   "elastic body plate (material=aluminum, mesh_size=5mm, element=tet4) { "
                   "box([100, 40, 10]); }\n"
                   "grip plate region=box([-1, -1, -1], [0.001, 41, 11]);\n"
                   "move plate by=[0, 10, 0] over=0.05s;\n"
                   "probe tip plate point=[100, 20, 5];\n"
                   "simulate(mode=dynamic, duration=0.08s, dt=0.5ms, frames=9);\n");
  const fs::path out = fresh_dir("grip");
  const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto& body = summary["bodies"][0];
  EXPECT_NEAR(body["position"][1].get<double>(), 0.020 + 0.010, 1e-12);       // the frame moved
  EXPECT_NEAR(summary["probes"]["tip"]["u"][1].get<double>(), 0.010, 0.001);  // and the plate
  EXPECT_GT(body["peak_reaction"].get<double>(), 0.0);          // the grip pulled it along
  EXPECT_FALSE(fs::exists(out / "meshes" / "plate_0000.vtu"));  // stl by default
  fs::remove_all(out);
}

TEST(Cli, PendulumOnARevoluteJointKeepsItsPeriod) {
  const fs::path out = fresh_dir("pendulum");
  const Result r = run("run " + std::string(VPROTO_SAMPLES) + "/pendulum.vp -o " + out.string() +
                       " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_LT(summary["max_joint_drift"].get<double>(), 1e-9);
  const auto rows = read_history(out / "history.csv");
  std::vector<double> crossings;
  for (std::size_t i = 1; i < rows.size(); ++i) {
    const double x0 = rows[i - 1].at("tip_ux"), x1 = rows[i].at("tip_ux");
    if (x0 < 0 && x1 >= 0)
      crossings.push_back(rows[i - 1].at("t") +
                          (rows[i].at("t") - rows[i - 1].at("t")) * -x0 / (x1 - x0));
  }
  ASSERT_GE(crossings.size(), 2u);
  const double period = (crossings.back() - crossings.front()) / (crossings.size() - 1);
  const double l = 0.5, b = 0.02, d = l / 2;
  const double expected = 2 * M_PI * std::sqrt(((b * b + l * l) / 12 + d * d) / (9.81 * d));
  EXPECT_NEAR(period, expected, 0.005 * expected);
  // and the hinge sample swings its leaf on the pin
  const fs::path hinge_out = fresh_dir("hinge");
  const Result h = run("run " + std::string(VPROTO_SAMPLES) + "/hinge.vp -o " + hinge_out.string() +
                       " --no-render --quiet");
  ASSERT_EQ(h.code, 0) << h.output;
  const auto hs = nlohmann::json::parse(std::ifstream(hinge_out / "summary.json"));
  EXPECT_LT(hs["max_joint_drift"].get<double>(), 1e-9);
  EXPECT_LT(hs["bodies"][1]["rotation"][0].get<double>(), 1 - 1e-6);  // the leaf turned
  fs::remove_all(out);
  fs::remove_all(hinge_out);
}

// Scripts that `run` must refuse: exit 2, the message, `where` (the script's name, or
// its name with a place), and nothing written.
struct Case {
  std::string script, message;
};

void expect_refused(const std::vector<Case>& cases, const std::string& name,
                    const std::string& where, const fs::path& out) {
  for (const Case& c : cases) {
    const fs::path script = write_script(name, c.script);
    const Result r = run("run " + script.string() + " -o " + out.string() + " --no-render");
    EXPECT_EQ(r.code, 2) << c.script << r.output;
    EXPECT_NE(r.output.find(c.message), std::string::npos) << c.script << r.output;
    EXPECT_NE(r.output.find(where), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << c.script;  // nothing written
  }
}

TEST(Cli, DynamicRunRefusesWhatItCannotHonour) {
  const fs::path out = fresh_dir("nodynamic");
  const std::string body =
      "elastic body b (material=steel, mesh_size=0.02) { box([0.2, 0.1, 0.05]); }\n";
  const std::vector<Case> cases = {
      {body + "move b by=[0, 0, 0.01] over=1s;\n", "nothing holds it to the frame"},
      // (a fixed frame without a clamp or grip: the quasistatic run failed on a singular K
      // with no body named, a dynamic one let contact push the material off the frame)
      {body + "fix b;\n", "has its reference frame fixed, but nothing holds it to the frame"},
      {body + "fix b;\nsimulate(mode=quasistatic, duration=1s);\n",
       "'fix b region=box([..], [..]);'"},
      {body + "torque b [0, 0, 1];\n", "torque on an elastic body"},
      {body + "fix b region=box([-1, -1, -1], [0.001, 1, 1]);\nvelocity b linear=[1, 0, 0];\n",
       "use 'move' to drive its grip"},
      {body + "fix b region=box([5, 5, 5], [6, 6, 6]);\n", "fix region selects no node"},
      {body + "fix b region=box([-1, -1, -1], [0.001, 1, 1]);\nprobe p b point=[1, 1, 1];\n",
       "probe point is outside body 'b'"},
      {"rigid body r (material=steel) { box(1); }\nexport(format=vtu);\n", "vtu export"},
      {body + "simulate(mass_damping=-1/1s);\n", "mass_damping must not be negative"},
      {body + "simulate(stiffness_damping=1/1s);\n", "stiffness_damping"},
      // a bound on the steps (issue 13: dt 1e-9 s ran for an hour, dt 1e-20 s for ever)
      {body + "simulate(duration=1s, dt=1e-9s);\n", "1e+09 steps, more than 5000000"},
      {body + "simulate(duration=1e30s);\n", "more than 5000000"},
  };
  expect_refused(cases, "vproto_cli_dyn.vp", "vproto_cli_dyn.vp", out);
}

// One paw pushed over a fixed catch and pulled back out, displacement-controlled: while
// the hook slides along the catch's face the paw is deflected by the interference, and
// the lateral force lies between the cantilever (E) and wide-plate (E / (1 - nu^2))
// values of P from y = P L^3 / 3EI -+ (mu P e) L^2 / 2EI (Bayer's P = 3 E I y / L^3 with
// the moment of the friction acting at the hook's apex, e off the paw's axis: stiffer on
// the way in, softer on the way out); the drive carries mu P, in on the way in, out on
// the way back; after the snap nothing touches.
TEST(Cli, AQuasistaticPawGivesItsInsertionAndRetentionForces) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path out = fresh_dir("pawrun");
  const Result r = run("run " + sample + " -o " + out.string() + " --size 320x240 --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["status"], "ok");
  EXPECT_EQ(summary["mode"], "quasistatic");
  EXPECT_NE(summary["note"].get<std::string>().find("no inertia"), std::string::npos);
  EXPECT_EQ(summary["solver"]["paw"]["factorizations"], 1);
  const auto curve = summary["reaction_curves"]["paw"];
  EXPECT_TRUE(fs::exists(out / curve["plot"].get<std::string>()));
  // the hook's roots on the paw's face are sharp inside corners: their hot-spot strain is
  // drawn against time
  const auto hot = summary["bodies"][0]["sharp_corner_hot_spot"];
  EXPECT_TRUE(fs::exists(out / hot["plot"].get<std::string>()));
  EXPECT_GT(hot["peak_strain"].get<double>(), 0);
  const double in = 0.0254, mu = 0.3, y = 0.06 * in, e = 0.25e9, nu = 0.44;
  const double inertia = 0.5 * in * std::pow(0.25 * in, 3) / 12;
  const double lever = (2 - 0.08) * in;       // root to the hook's apex
  const double offset = (0.125 + 0.08) * in;  // the apex from the paw's axis
  auto beam = [&](double sign) {
    return 3 * e * inertia * y / (std::pow(lever, 3) - sign * 1.5 * mu * offset * lever * lever);
  };
  const auto rows = read_history(out / "history.csv");
  ASSERT_GT(rows.size(), 150u);
  int sliding_in = 0, sliding_out = 0, after_snap = 0;
  double push_sliding = 0;
  for (const auto& row : rows) {
    const double travel = rows.front().at("paw_z") - row.at("paw_z");  // down is in
    const bool going_in = row.at("t") < 1.0;
    if (travel > 8e-3 && travel < 18e-3) {  // the hook's apex on the catch's face
      const double lateral = std::abs(row.at("paw_rx")), along = row.at("paw_rz");
      EXPECT_NEAR(row.at("hook_ux"), y, 0.02 * y);
      const double p = beam(going_in ? 1 : -1);
      EXPECT_GT(lateral, p);
      EXPECT_LT(lateral, p / (1 - nu * nu));
      // the reaction along the drive (-z) is mu P against the motion
      EXPECT_NEAR(going_in ? -along : along, mu * lateral, 0.01 * mu * lateral);
      if (going_in) push_sliding = -along;
      ++(going_in ? sliding_in : sliding_out);
    }
    if (going_in && travel > 23e-3) {  // snapped under the catch
      EXPECT_EQ(row.at("contacts"), 0);
      EXPECT_LT(std::abs(row.at("hook_ux")), 1e-9);
      ++after_snap;
    }
  }
  EXPECT_GT(sliding_in, 20);
  EXPECT_GT(sliding_out, 20);
  EXPECT_GT(after_snap, 5);
  // the lead face takes more than sliding along the face; pulling out is a pull
  EXPECT_GT(curve["peak_push"].get<double>(), 2 * push_sliding);
  EXPECT_LT(curve["peak_pull"].get<double>(), -2 * push_sliding);
  // nothing overlaps by more than 1/500 of the mesh size at a step's start
  EXPECT_LT(summary["elastic_contact"]["max_penetration"].get<double>(), 2e-3 * 0.1 * in);
  // a finer mesh (0.07 in) gives the same curve: sliding force within 1 %, peaks within 2 %
  const fs::path fine = fresh_dir("pawfine");
  const Result rf =
      run("run " + sample + " -o " + fine.string() + " --no-render --quiet --set mesh=0.07in");
  ASSERT_EQ(rf.code, 0) << rf.output;
  const auto sf = nlohmann::json::parse(std::ifstream(fine / "summary.json"));
  EXPECT_GT(sf["solver"]["paw"]["dofs"].get<long>(), summary["solver"]["paw"]["dofs"].get<long>());
  const auto cf = sf["reaction_curves"]["paw"];
  EXPECT_NEAR(cf["peak_push"].get<double>(), curve["peak_push"].get<double>(),
              0.02 * curve["peak_push"].get<double>());
  EXPECT_NEAR(cf["peak_pull"].get<double>(), curve["peak_pull"].get<double>(),
              0.02 * std::abs(curve["peak_pull"].get<double>()));
  const auto fine_rows = read_history(fine / "history.csv");
  double fine_push = 0;
  for (const auto& row : fine_rows) {
    const double travel = fine_rows.front().at("paw_z") - row.at("paw_z");
    if (row.at("t") < 1.0 && travel > 8e-3 && travel < 18e-3) fine_push = -row.at("paw_rz");
  }
  EXPECT_NEAR(fine_push, push_sliding, 0.01 * push_sliding);
  fs::remove_all(out);
  fs::remove_all(fine);
}

// The same paw against CalculiX 2.20 (bench/calculix_paw.py: the same tet10 mesh as C3D10,
// node-to-face penalty contact at 1e11 N/m per node, each pair with the normal of the face
// touched, 400 increments), its figures recorded in docs/paw_calculix.json at
// mesh 0.1 in: the force along the drive and the lateral force while the lead face rides
// over the catch's edge (at 0.26 in of travel) and while the apex slides on its face (the
// mean over 0.40..0.60 in), and the travel where the hook is home (the lateral force gone:
// 0.84 in, where the return face's point at the catch's face passes its lower edge;
// CalculiX got there, 21.32 mm, on the mesh before the CSG's canonical order, and stopped
// converging at 19.6 and 20.8 mm on this one), without and with friction. (Remeasured
// 2026-11-28 on the 2,332-node mesh of the CSG's canonical order.)
TEST(Cli, AQuasistaticPawAgreesWithCalculixOnTheSameMesh) {
  struct Reference {
    double mu, push_lead, lateral_lead, push_sliding, lateral_sliding, home;
  };
  const Reference references[] = {{0.0, 2.64273, 2.47574, 0.0, 2.76539, 21.336e-3},
                                  {0.3, 5.72185, 2.87736, 0.87167, 2.90557, 21.336e-3}};
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const double in = 0.0254;
  for (const Reference& ref : references) {
    SCOPED_TRACE("mu = " + std::to_string(ref.mu));
    const fs::path out = fresh_dir("pawccx");
    const Result r =
        run("run " + sample + " -o " + out.string() +
            " --no-render --quiet --dt 0.002 --duration 0.85 --set mu=" + std::to_string(ref.mu));
    ASSERT_EQ(r.code, 0) << r.output;
    const auto rows = read_history(out / "history.csv");
    ASSERT_GT(rows.size(), 400u);
    // (travel, lateral, push) per increment; the drive goes down at 1.1 in/s
    auto travel = [&](const auto& row) { return rows.front().at("paw_z") - row.at("paw_z"); };
    auto at = [&](double s, const char* column, double sign) {
      for (std::size_t k = 1; k < rows.size(); ++k) {
        const double s0 = travel(rows[k - 1]), s1 = travel(rows[k]);
        if (s0 <= s && s <= s1) {
          const double w = (s - s0) / (s1 - s0);
          return sign * ((1 - w) * rows[k - 1].at(column) + w * rows[k].at(column));
        }
      }
      ADD_FAILURE() << "travel " << s << " not reached";
      return 0.0;
    };
    EXPECT_NEAR(at(0.26 * in, "paw_rz", -1), ref.push_lead, 0.01 * ref.push_lead);
    EXPECT_NEAR(at(0.26 * in, "paw_rx", -1), ref.lateral_lead, 0.01 * ref.lateral_lead);
    double push = 0, lateral = 0, home = 0;
    int n = 0;
    for (const auto& row : rows) {
      if (travel(row) >= 0.40 * in && travel(row) <= 0.60 * in) {
        push -= row.at("paw_rz");
        lateral -= row.at("paw_rx");
        ++n;
      }
      if (home == 0 && travel(row) > 0.7 * in && n > 0 &&
          std::abs(row.at("paw_rx")) < 0.01 * lateral / n)
        home = travel(row);
    }
    ASSERT_GT(n, 50);
    EXPECT_NEAR(push / n, ref.push_sliding, 0.01 * ref.push_sliding + 1e-6);
    EXPECT_NEAR(lateral / n, ref.lateral_sliding, 0.005 * ref.lateral_sliding);
    EXPECT_NEAR(home, ref.home, 0.005 * ref.home);
    fs::remove_all(out);
  }
}

TEST(Cli, QuasistaticRunRefusesFramesNothingHolds) {
  const fs::path out = fresh_dir("noquasi");
  const std::string body =
      "elastic body b (material=steel, mesh_size=0.02) { box([0.2, 0.1, 0.05]); }\n"
      "simulate(mode=quasistatic, duration=1s, frames=3);\n";
  const std::string grip = "grip b region=box([-1, -1, 0.049], [1, 1, 1]);\n";
  const std::vector<Case> cases = {
      {body + grip + "joint slider b axis=[0, 0, 1];\n", "a joint leaves its body free"},
      {body + grip + "force b [0, 0, -10];\n", "whose frame nothing holds"},
      {body + grip, "gripped to a frame that nothing fixes or drives"},
      {body + "force b [0, 0, -10] region=box([-1, -1, 0.049], [1, 1, 1]);\n",
       "nothing holds elastic body 'b'"},
      {body + "rigid body r (material=steel) { translate([0, 0, -1]) box(0.5); }\n"
              "fix b region=box([-1, -1, -1], [0.001, 1, 1]);\ngravity [0, 0, -9.81];\n",
       "gravity would pull rigid body 'r'"},
  };
  expect_refused(cases, "vproto_cli_quasi.vp", "vproto_cli_quasi.vp:", out);
}

}  // namespace

namespace {

// mpirun as root needs --allow-run-as-root; --oversubscribe lets 2 ranks run beside the
// other tests on 2 cores
std::string mpirun(int ranks) {
  return "mpirun --allow-run-as-root --oversubscribe -np " + std::to_string(ranks) + " " +
         VPROTO_EXE + " ";
}

bool can_run_mpi() {
  return vproto::sim::petsc_available() && std::system("command -v mpirun > /dev/null 2>&1") == 0;
}

// the scratch folders other ranks made for the run into `out` (named after it: other
// tests' ranks may be running beside this one)
int scratch_folders_of_other_ranks(const fs::path& out) {
  int n = 0;
  const std::string tail = "-" + out.filename().string();
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path())) {
    const std::string name = e.path().filename().string();
    n += name.rfind("vproto-rank", 0) == 0 && name.size() > tail.size() &&
         name.compare(name.size() - tail.size(), tail.size(), tail) == 0;
  }
  return n;
}

// Issue 12: `mpirun -np 2 vproto run` shares the static solve between two ranks (PETSc,
// CG + GAMG) and gives CHOLMOD's answer to the solver's tolerance; rank 0 alone writes.
TEST(Cli, TwoMpiRanksShareAStaticSolveAndAgreeWithCholmod) {
  if (!can_run_mpi()) GTEST_SKIP() << "built without PETSc, or no mpirun";
  const std::string sample = std::string(VPROTO_SAMPLES) + "/cantilever.vp";
  const fs::path one = fresh_dir("mpi_static_1"), two = fresh_dir("mpi_static_2");
  const Result a = run("run " + sample + " -o " + one.string() +
                       " --set size=20mm --frames 2 --size 160x90 --solver cholmod --quiet");
  ASSERT_EQ(a.code, 0) << a.output;
  const Result b = shell(mpirun(2) + "run " + sample + " -o " + two.string() +
                         " --set size=20mm --frames 2 --size 160x90");
  ASSERT_EQ(b.code, 0) << b.output;
  // one report on the terminal, one set of outputs
  std::size_t done = 0;
  for (std::size_t at = b.output.find("done: static solve"); at != std::string::npos;
       at = b.output.find("done: static solve", at + 1))
    ++done;
  EXPECT_EQ(done, 1u) << b.output;
  EXPECT_TRUE(fs::exists(two / "frames" / "frame_0001.png"));
  EXPECT_EQ(scratch_folders_of_other_ranks(two), 0);
  const auto s1 = nlohmann::json::parse(std::ifstream(one / "summary.json"));
  const auto s2 = nlohmann::json::parse(std::ifstream(two / "summary.json"));
  EXPECT_EQ(s1["solver"]["beam"]["backend"], "cholmod");
  const auto& p = s2["solver"]["beam"];
  EXPECT_EQ(p["backend"], "petsc");
  EXPECT_EQ(p["ranks"], 2);
  EXPECT_NE(p["reason"].get<std::string>().find("2 MPI ranks"), std::string::npos) << p;
  // no rank assembled the whole matrix: each computed the elements of its own rows
  EXPECT_NE(p["method"].get<std::string>().find("each rank's rows from its own elements"),
            std::string::npos)
      << p;
  const double tol = p["relative_tolerance"];
  EXPECT_GT(tol, 0);
  EXPECT_LE(p["relative_residual"].get<double>(), tol);
  // the displacement error is at most about sqrt(cond K) ~ l/h = 50 times the residual
  const double tip1 = s1["probes"]["tip"]["u"][2], tip2 = s2["probes"]["tip"]["u"][2];
  EXPECT_NEAR(tip2, tip1, 50 * tol * std::abs(tip1));
  const double e1 = s1["energy"]["strain"], e2 = s2["energy"]["strain"];
  EXPECT_NEAR(e2, e1, 50 * tol * e1);
  EXPECT_NEAR(s2["bodies"][0]["reaction"][2].get<double>(), 100.0, 1e-6);
  // the same iterations as PETSc on one rank: each rank sums its rows' part of the coarse
  // operator P^T K P, and the parts of other ranks' rows reach them (without them the
  // preconditioner would differ and CG would take other steps)
  const fs::path lone = fresh_dir("mpi_static_petsc_1");
  const Result c = run("run " + sample + " -o " + lone.string() +
                       " --set size=20mm --no-render --export none --solver petsc --quiet");
  ASSERT_EQ(c.code, 0) << c.output;
  const auto s3 = nlohmann::json::parse(std::ifstream(lone / "summary.json"));
  EXPECT_EQ(s3["solver"]["beam"]["method"], "CG + p-multigrid (tet10 to tet4, MUMPS on tet4)");
  EXPECT_EQ(p["iterations"], s3["solver"]["beam"]["iterations"]);
  EXPECT_NEAR(p["relative_residual"].get<double>(),
              s3["solver"]["beam"]["relative_residual"].get<double>(), 1e-6 * tol);
  fs::remove_all(lone);
  // each rank's peak memory, gathered
  ASSERT_EQ(s2["memory"]["peak_bytes_per_rank"].size(), 2u);
  for (const auto& bytes : s2["memory"]["peak_bytes_per_rank"]) EXPECT_GT(bytes.get<double>(), 1e6);
  EXPECT_EQ(s1["memory"]["peak_bytes_per_rank"].size(), 1u);
  fs::remove_all(one);
  fs::remove_all(two);
}

// The Newmark steps on two ranks: one MUMPS factor kept for every step, the same history
// as CHOLMOD's to 5e-6 (two factors' round-off, grown over 20 steps: below 1e-6 on the
// machines of 2026-11-25, 1.4e-6 on a fresh one of 2026-11-26 at the commit before).
TEST(Cli, TwoMpiRanksStepAnElasticBodyOnOneKeptMumpsFactor) {
  if (!can_run_mpi()) GTEST_SKIP() << "built without PETSc, or no mpirun";
  const std::string sample = std::string(VPROTO_SAMPLES) + "/cantilever_vibration.vp";
  const fs::path one = fresh_dir("mpi_dyn_1"), two = fresh_dir("mpi_dyn_2");
  const std::string opts = " --set size=25mm --duration 12ms --frames 3 --no-render --quiet";
  const Result a = run("run " + sample + " -o " + one.string() + opts);
  ASSERT_EQ(a.code, 0) << a.output;
  const Result b = shell(mpirun(2) + "run " + sample + " -o " + two.string() + opts);
  ASSERT_EQ(b.code, 0) << b.output;
  const auto s2 = nlohmann::json::parse(std::ifstream(two / "summary.json"));
  EXPECT_EQ(s2["solver"]["beam"]["backend"], "petsc");
  EXPECT_EQ(s2["solver"]["beam"]["factorizations"], 1);
  EXPECT_EQ(s2["solver"]["beam"]["method"], "MUMPS Cholesky (distributed factor, kept)");
  const auto h1 = read_history(one / "history.csv"), h2 = read_history(two / "history.csv");
  ASSERT_EQ(h1.size(), h2.size());
  const auto &r1 = h1.back(), &r2 = h2.back();
  ASSERT_GT(r1.size(), 3u);
  // to 5e-6 of each vector's size: a component near zero (the tip's sideways motion, 4e-10
  // m against 6e-4 m down; the clamp's sideways reaction, 7e-5 N against 295 N) carries the
  // round-off of the others (on the mesh of the canonically ordered CSG: 7e-5 of itself)
  auto scale = [&](const std::string& column) {
    const char axis = column.back();
    if (column.size() < 2 || (axis != 'x' && axis != 'y' && axis != 'z'))
      return std::abs(r1.at(column));
    const std::string stem = column.substr(0, column.size() - 1);
    double largest = 0;
    for (const char* a : {"x", "y", "z"})
      if (const auto it = r1.find(stem + a); it != r1.end())
        largest = std::max(largest, std::abs(it->second));
    return largest;
  };
  for (const auto& [column, value] : r1)
    EXPECT_NEAR(r2.at(column), value, 5e-6 * scale(column) + 1e-15) << column;
  fs::remove_all(one);
  fs::remove_all(two);
}

// A bad script under mpirun: every rank meets the error, rank 0 reports it once, the exit
// code is cli.md's, and nothing is written.
TEST(Cli, AnErrorUnderMpiIsReportedOnceWithItsExitCode) {
  if (!can_run_mpi()) GTEST_SKIP() << "built without PETSc, or no mpirun";
  const fs::path bad = write_script("vproto_cli_mpi_bad.vp",
                                    "elastic body b (material=steel, mesh_size=0.01) {\n"
                                    "  box([0.1, 0.1, 0.1]);\n}\nfix b region=box([9, 9, 9], "
                                    "[10, 10, 10]);\nsimulate(mode=static);\n");
  const fs::path out = fresh_dir("mpi_bad");
  const Result r = shell(mpirun(2) + "run " + bad.string() + " -o " + out.string() + " --quiet");
  EXPECT_EQ(r.code, 2) << r.output;
  const std::string what = "selects no node";
  const std::size_t first = r.output.find(what);
  EXPECT_NE(first, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(what, first + 1), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "summary.json"));
}

TEST(Cli, TheSolverOptionIsChecked) {
  const Result r = run("run " + std::string(VPROTO_SAMPLES) + "/cantilever.vp -o " +
                       fresh_dir("badsolver").string() + " --solver pardiso");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--solver must be auto, cholmod or petsc, got 'pardiso'"),
            std::string::npos)
      << r.output;
  const fs::path script = write_script(
      "vproto_cli_solver.vp",
      "elastic body b (material=steel, mesh_size=0.02) { box([0.1, 0.1, 0.1]); }\n"
      "fix b region=box([-1, -1, -1], [0.001, 1, 1]);\nsimulate(mode=static, solver=umfpack);\n");
  const Result s = run("check " + script.string());
  EXPECT_EQ(s.code, 2);
  EXPECT_NE(s.output.find("vproto_cli_solver.vp:3:"), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("umfpack"), std::string::npos) << s.output;
}

}  // namespace

namespace {

std::vector<std::map<std::string, std::string>> csv_rows(const fs::path& file) {
  std::ifstream in(file);
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::stringstream head(line); std::getline(head, line, ',');) names.push_back(line);
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    std::map<std::string, std::string> row;
    std::stringstream cells(line);
    std::string cell;
    for (std::size_t k = 0; k < names.size() && std::getline(cells, cell, ','); ++k)
      row[names[k]] = cell;
    rows.push_back(row);
  }
  return rows;
}

// Issue 12: `vproto sweep` runs every combination of the lists, each a full run, and its
// table holds what each run reports (checked against a run of one variant on its own);
// the insertion force grows with the interference at either hook angle.
TEST(Cli, SweepRunsEveryCombinationAndTabulatesWhatEachRunReports) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path out = fresh_dir("sweep");
  const Result r = run("sweep " + sample + " -o " + out.string() +
                       " --set interference=0.03in,0.06in --set hook_angle=30deg,45deg"
                       " --no-render --quiet");
  ASSERT_EQ(r.code, 0) << r.output;
  const auto rows = csv_rows(out / "sweep.csv");
  ASSERT_EQ(rows.size(), 4u);
  // the first --set outermost
  EXPECT_EQ(rows[0].at("interference"), "0.03in");
  EXPECT_EQ(rows[0].at("hook_angle"), "30deg");
  EXPECT_EQ(rows[1].at("hook_angle"), "45deg");
  EXPECT_EQ(rows[2].at("interference"), "0.06in");
  EXPECT_NEAR(std::stod(rows[2].at("interference_si")), 0.06 * 0.0254, 1e-12);
  EXPECT_NEAR(std::stod(rows[1].at("hook_angle_si")), M_PI / 4, 1e-9);
  for (const auto& row : rows) {
    EXPECT_EQ(row.at("exit"), "0");
    EXPECT_GT(std::stod(row.at("reaction_curves.paw.peak_push")), 0);
    EXPECT_LT(std::stod(row.at("reaction_curves.paw.peak_pull")), 0);
  }
  for (int angle : {0, 1}) {
    EXPECT_GT(std::stod(rows[2 + angle].at("reaction_curves.paw.peak_push")),
              std::stod(rows[angle].at("reaction_curves.paw.peak_push")));
    // the root's strain against LDPE's yield strain: Bayer's 1.5 h y / l^2, twice the
    // deflection, about twice the strain
    const std::string ratio = "bodies.paw.yield.away_from_contact_and_corners.strain_ratio";
    const double lower = std::stod(rows[angle].at(ratio)),
                 higher = std::stod(rows[2 + angle].at(ratio));
    EXPECT_GT(higher, 1.6 * lower) << lower << " " << higher;
    EXPECT_LT(higher, 2.4 * lower) << lower << " " << higher;
  }
  EXPECT_TRUE(fs::exists(out / "plots" / "sweep_reaction_curves_paw_peak_push.png"));
  EXPECT_TRUE(fs::exists(out / ".vproto-cache"));  // one cache for every variant
  // one variant on its own gives the row's figures
  const fs::path alone = fresh_dir("sweep_alone");
  const Result a = run("run " + sample + " -o " + alone.string() +
                       " --set interference=0.06in --set hook_angle=45deg --no-render --quiet");
  ASSERT_EQ(a.code, 0) << a.output;
  const auto s = nlohmann::json::parse(std::ifstream(alone / "summary.json"));
  const double push = s["reaction_curves"]["paw"]["peak_push"];
  EXPECT_NEAR(std::stod(rows[3].at("reaction_curves.paw.peak_push")), push, 1e-8 * push);
  fs::remove_all(out);
  fs::remove_all(alone);
}

TEST(Cli, SweepRefusesBadListsBeforeRunningAnything) {
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path out = fresh_dir("sweep_bad");
  const Result empty = run("sweep " + sample + " -o " + out.string() + " --set mu=0.1,,0.3");
  EXPECT_EQ(empty.code, 2);
  EXPECT_NE(empty.output.find("an empty value in the list"), std::string::npos) << empty.output;
  const Result units =
      run("sweep " + sample + " -o " + out.string() + " --set interference=0.03in,3kg");
  EXPECT_EQ(units.code, 2);
  EXPECT_NE(units.output.find("is a length in the script"), std::string::npos) << units.output;
  EXPECT_NE(units.output.find("variant interference=3kg"), std::string::npos) << units.output;
  const Result twice =
      run("sweep " + sample + " -o " + out.string() + " --set mu=0.1,0.2 --set mu=0.3");
  EXPECT_EQ(twice.code, 2);
  EXPECT_NE(twice.output.find("--set mu is given twice"), std::string::npos) << twice.output;
  const Result none = run("sweep " + sample + " -o " + out.string());
  EXPECT_EQ(none.code, 2);
  EXPECT_FALSE(fs::exists(out));  // nothing ran, nothing written
}

// The variants spread over two MPI ranks (each runs whole variants with solves of its own)
// give the table one process gives: to 1e-3. (Under mpirun each rank's runs factor with
// MUMPS (solver=auto), the single process's with CHOLMOD. The peak is sampled at the end
// of the increment before the apex passes the catch's edge, which ends at the contact
// stage's pass limit with the contact force settled to 2 %: the two factors' round-off
// shows there at 1.4e-4, elsewhere below 1e-5.)
TEST(Cli, SweepOverTwoMpiRanksGivesTheSameTable) {
  if (!can_run_mpi()) GTEST_SKIP() << "built without PETSc, or no mpirun";
  const std::string sample = std::string(VPROTO_SAMPLES) + "/paw_quasistatic.vp";
  const fs::path one = fresh_dir("sweep_1"), two = fresh_dir("sweep_2");
  const std::string lists = " --set interference=0.03in,0.045in,0.06in --no-render --quiet";
  const Result a = run("sweep " + sample + " -o " + one.string() + lists);
  ASSERT_EQ(a.code, 0) << a.output;
  const Result b = shell(mpirun(2) + "sweep " + sample + " -o " + two.string() + lists);
  ASSERT_EQ(b.code, 0) << b.output;
  const auto r1 = csv_rows(one / "sweep.csv"), r2 = csv_rows(two / "sweep.csv");
  ASSERT_EQ(r1.size(), 3u);
  ASSERT_EQ(r2.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i)
    for (const char* key : {"reaction_curves.paw.peak_push", "reaction_curves.paw.peak_pull"}) {
      const double x = std::stod(r1[i].at(key)), y = std::stod(r2[i].at(key));
      EXPECT_NEAR(y, x, 1e-3 * std::abs(x)) << key << " row " << i;
    }
  fs::remove_all(one);
  fs::remove_all(two);
}

}  // namespace
