#include "vproto/sim/contact_problem_io.h"

#include <bit>
#include <cstdio>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

namespace vproto::sim {

namespace {

constexpr const char* kMagic = "vproto-contact-problem";
constexpr int kVersion = 1;

static_assert(std::endian::native == std::endian::little,
              "the contact problem files are little-endian doubles");

void write_doubles(std::ofstream& out, const double* data, Eigen::Index count) {
  out.write(reinterpret_cast<const char*>(data),
            static_cast<std::streamsize>(count) * static_cast<std::streamsize>(sizeof(double)));
}

void read_doubles(std::ifstream& in, double* data, Eigen::Index count, const std::string& path) {
  in.read(reinterpret_cast<char*>(data),
          static_cast<std::streamsize>(count) * static_cast<std::streamsize>(sizeof(double)));
  if (!in) throw std::runtime_error(path + ": cut short (fewer numbers than its header says)");
}

}  // namespace

void write_contact_problem(const std::string& path, const PointContactProblem& problem,
                           const Eigen::VectorXd& warm, const PointContactOptions& options) {
  const Eigen::Index rows = problem.free.size(), m = rows / 3;
  if (problem.columns || problem.w.rows() != rows || problem.w.cols() != rows ||
      static_cast<Eigen::Index>(problem.mu.size()) != m || rows != 3 * m ||
      (warm.size() != 0 && warm.size() != rows))
    throw std::runtime_error(path + ": not a dense problem of consistent sizes");
  const std::string temporary = path + ".part";
  {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error(path + ": cannot be written");
    std::ostringstream header;
    header.precision(17);
    header << kMagic << ' ' << kVersion << " points=" << m << " warm=" << (warm.size() ? 1 : 0)
           << " max_sweeps=" << options.max_sweeps << " tolerance=" << options.tolerance
           << " newton_after=" << options.newton_after
           << " newton_unknowns=" << options.newton_unknowns
           << " block_stick=" << (options.block_stick ? 1 : 0)
           << " newton_tries=" << options.newton_tries
           << " newton_damping=" << options.newton_damping
           << " newton_damping_floor=" << options.newton_damping_floor << '\n';
    out << header.str();
    write_doubles(out, problem.w.data(), rows * rows);
    write_doubles(out, problem.free.data(), rows);
    write_doubles(out, problem.mu.data(), m);
    if (warm.size()) write_doubles(out, warm.data(), rows);
    if (!out) throw std::runtime_error(path + ": writing failed (disk full?)");
  }
  if (std::rename(temporary.c_str(), path.c_str()) != 0)
    throw std::runtime_error(path + ": cannot be written");
}

void read_contact_problem(const std::string& path, PointContactProblem* problem,
                          Eigen::VectorXd* warm, PointContactOptions* options) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot be read");
  std::string line;
  std::getline(in, line);
  std::istringstream header(line);
  std::string magic;
  int version = 0;
  header >> magic >> version;
  if (magic != kMagic)
    throw std::runtime_error(path + ": not a contact problem (written by VPROTO_DUMP_CONTACT)");
  if (version != kVersion)
    throw std::runtime_error(path + ": version " + std::to_string(version) + ", this reads " +
                             std::to_string(kVersion));
  std::map<std::string, double> field;
  for (std::string item; header >> item;) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) throw std::runtime_error(path + ": bad header item " + item);
    try {
      field[item.substr(0, eq)] = std::stod(item.substr(eq + 1));
    } catch (const std::logic_error&) {
      throw std::runtime_error(path + ": bad header item " + item);
    }
  }
  auto get = [&](const char* key) {
    const auto found = field.find(key);
    if (found == field.end()) throw std::runtime_error(path + ": header lacks " + key);
    return found->second;
  };
  const auto m = static_cast<Eigen::Index>(get("points")), rows = 3 * m;
  if (m <= 0) throw std::runtime_error(path + ": no points");
  options->max_sweeps = static_cast<int>(get("max_sweeps"));
  options->tolerance = get("tolerance");
  options->newton_after = static_cast<int>(get("newton_after"));
  options->newton_unknowns = static_cast<Eigen::Index>(get("newton_unknowns"));
  options->block_stick = get("block_stick") != 0;
  options->newton_tries = static_cast<int>(get("newton_tries"));
  options->newton_damping = get("newton_damping");
  options->newton_damping_floor = get("newton_damping_floor");
  problem->columns = nullptr;
  problem->w.resize(rows, rows);
  problem->free.resize(rows);
  problem->mu.resize(static_cast<std::size_t>(m));
  read_doubles(in, problem->w.data(), rows * rows, path);
  read_doubles(in, problem->free.data(), rows, path);
  read_doubles(in, problem->mu.data(), m, path);
  warm->resize(get("warm") != 0 ? rows : 0);
  if (warm->size()) read_doubles(in, warm->data(), rows, path);
  if (in.peek() != std::char_traits<char>::eof())
    throw std::runtime_error(path + ": longer than its header says");
}

}  // namespace vproto::sim
