#include "vproto/sim/contact_problem_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>

namespace vproto::sim {
namespace {

// Three points pressed on a coupled, not symmetric W (as a floating body's is), one of them
// sliding: a problem whose solution the file must give back to the bit.
PointContactProblem three_points() {
  PointContactProblem p;
  Eigen::MatrixXd a(9, 9);
  for (int i = 0; i < 9; ++i)
    for (int j = 0; j < 9; ++j) a(i, j) = std::sin(1.0 + 3 * i + 7 * j);
  p.w = a * a.transpose() + 9 * Eigen::MatrixXd::Identity(9, 9);
  p.w(0, 4) += 0.3;  // the frame's inertial part: not symmetric
  p.free.resize(9);
  p.free << -1, 0.2, 0, -0.5, 3, -1, 0.4, 0, 0;
  p.mu = {0.3, 0.2, 0.5};
  return p;
}

std::string temporary(const char* name) { return ::testing::TempDir() + name; }

TEST(ContactProblemIo, WritesAndReadsBackTheProblemItsStartAndOptions) {
  const PointContactProblem p = three_points();
  const Eigen::VectorXd warm = Eigen::VectorXd::LinSpaced(9, 0.5, 1.5);
  PointContactOptions o;
  o.max_sweeps = 77;
  o.tolerance = 1.0 / 3.0 * 1e-12;  // (all 17 digits kept)
  o.newton_after = 3;
  o.newton_unknowns = 600;
  o.block_stick = false;
  o.newton_tries = 2;
  o.newton_damping = 1e-6;
  o.newton_damping_floor = 1e-9;
  const std::string path = temporary("three_points.bin");
  write_contact_problem(path, p, warm, o);
  EXPECT_FALSE(std::filesystem::exists(path + ".part"));
  PointContactProblem q;
  Eigen::VectorXd warm_read;
  PointContactOptions r;
  read_contact_problem(path, &q, &warm_read, &r);
  EXPECT_EQ(q.w, p.w);
  EXPECT_EQ(q.free, p.free);
  EXPECT_EQ(q.mu, p.mu);
  EXPECT_EQ(warm_read, warm);
  EXPECT_EQ(r.max_sweeps, 77);
  EXPECT_EQ(r.tolerance, o.tolerance);
  EXPECT_EQ(r.newton_after, 3);
  EXPECT_EQ(r.newton_unknowns, 600);
  EXPECT_FALSE(r.block_stick);
  EXPECT_EQ(r.newton_tries, 2);
  EXPECT_EQ(r.newton_damping, 1e-6);
  EXPECT_EQ(r.newton_damping_floor, 1e-9);
  // the same solve, to the bit
  const PointContactSolution a = solve_point_contacts(p, warm, o),
                             b = solve_point_contacts(q, warm_read, r);
  EXPECT_TRUE(a.converged);
  EXPECT_GT(a.lambda[0], 0);
  EXPECT_EQ(a.lambda, b.lambda);
  EXPECT_EQ(a.newton_iterations, b.newton_iterations);
  // no warm start: none read back
  write_contact_problem(path, p, Eigen::VectorXd(), o);
  read_contact_problem(path, &q, &warm_read, &r);
  EXPECT_EQ(warm_read.size(), 0);
  EXPECT_EQ(q.w, p.w);
}

TEST(ContactProblemIo, RefusesOtherFilesFilesCutShortAndProblemsOfWrongSizes) {
  const PointContactProblem p = three_points();
  PointContactProblem q;
  Eigen::VectorXd warm;
  PointContactOptions o;
  auto refused = [&](const std::string& path, const std::string& says) {
    try {
      read_contact_problem(path, &q, &warm, &o);
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_NE(what.find(says), std::string::npos) << what;
      return;
    }
    ADD_FAILURE() << path << " was read";
  };
  refused(temporary("missing.bin"), "cannot be read");
  const std::string text = temporary("text.bin");
  std::ofstream(text) << "units length=mm;\n";
  refused(text, "not a contact problem");
  // cut short, and longer than its header says
  const std::string path = temporary("cut.bin");
  write_contact_problem(path, p, Eigen::VectorXd(), o);
  const auto size = std::filesystem::file_size(path);
  std::filesystem::resize_file(path, size - 8);
  refused(path, "cut short");
  std::filesystem::resize_file(path, size + 8);
  refused(path, "longer than its header says");
  // a newer version
  write_contact_problem(path, p, Eigen::VectorXd(), o);
  {
    std::fstream f(path, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(static_cast<std::streamoff>(std::string("vproto-contact-problem ").size()));
    f.put('9');
  }
  refused(path, "version 9");
  // sizes that do not agree are not written
  PointContactProblem bad = p;
  bad.mu.pop_back();
  EXPECT_THROW(write_contact_problem(path, bad, Eigen::VectorXd(), o), std::runtime_error);
  EXPECT_THROW(write_contact_problem(path, p, Eigen::VectorXd::Zero(4), o), std::runtime_error);
}

}  // namespace
}  // namespace vproto::sim
