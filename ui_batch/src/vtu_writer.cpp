#include "vproto/ui_batch/vtu_writer.h"

#include <cstdint>
#include <cstring>
#include <fstream>

#include "vproto/materials/errors.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch {
namespace {

// The arrays go after the XML as raw little-endian blocks (VTK's appended data, each block
// led by its byte count as a UInt64): 17 digits of ASCII per number cost a 10k-node
// plate's 60 ramp frames 2.1 s of writing; raw bytes are a third of the size and written
// at the disk's speed. The cell types stay ASCII (one small number per cell).
class Appended {
 public:
  /// Declares a Float64 or Int64 array and queues its values; returns its XML element.
  template <typename T>
  std::string array(const char* type, const std::string& name, int components,
                    std::vector<T> values) {
    std::string xml = std::string("<DataArray type=\"") + type + "\"";
    if (!name.empty()) xml += " Name=\"" + name + "\"";
    xml += " NumberOfComponents=\"" + std::to_string(components) + "\" format=\"appended\" " +
           "offset=\"" + std::to_string(offset_) + "\"/>\n";
    const std::uint64_t bytes = values.size() * sizeof(T);
    std::string block(sizeof bytes + bytes, '\0');
    std::memcpy(block.data(), &bytes, sizeof bytes);
    if (bytes) std::memcpy(block.data() + sizeof bytes, values.data(), bytes);
    offset_ += block.size();
    blocks_.push_back(std::move(block));
    return xml;
  }
  void write(std::ostream& out) const {
    out << "<AppendedData encoding=\"raw\">\n_";
    for (const auto& b : blocks_) out.write(b.data(), static_cast<std::streamsize>(b.size()));
    out << "\n</AppendedData>\n";
  }

 private:
  std::size_t offset_ = 0;
  std::vector<std::string> blocks_;
};

std::vector<double> row_major(const Eigen::MatrixXd& m) {
  std::vector<double> v(static_cast<std::size_t>(m.size()));
  std::size_t k = 0;
  for (Eigen::Index i = 0; i < m.rows(); ++i)
    for (Eigen::Index j = 0; j < m.cols(); ++j) v[k++] = m(i, j);
  return v;
}

}  // namespace

void write_vtu(const geometry::TetMesh& mesh, const std::string& path,
               const Eigen::MatrixX3d& nodes, const std::vector<PointField>& fields) {
  static_assert(sizeof(double) == 8 && sizeof(std::int64_t) == 8);
  const Eigen::MatrixX3d& x = nodes.rows() ? nodes : mesh.nodes;
  const Eigen::Index n = x.rows(), e = mesh.elements.rows(), per = mesh.elements.cols();
  Appended data;
  const std::string points = data.array("Float64", "", 3, row_major(x));
  std::vector<std::int64_t> connectivity(static_cast<std::size_t>(e * per)), offsets;
  offsets.reserve(static_cast<std::size_t>(e));
  for (Eigen::Index c = 0; c < e; ++c) {
    for (Eigen::Index k = 0; k < per; ++k)
      connectivity[static_cast<std::size_t>(c * per + k)] = mesh.elements(c, k);
    offsets.push_back((c + 1) * per);
  }
  const std::string cells = data.array("Int64", "connectivity", 1, std::move(connectivity)) +
                            data.array("Int64", "offsets", 1, std::move(offsets));
  std::string point_data;
  for (const auto& [name, values] : fields)
    point_data += data.array("Float64", name, static_cast<int>(values.cols()), row_major(values));
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
           "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n"
           "<Piece NumberOfPoints=\""
        << n << "\" NumberOfCells=\"" << e << "\">\n<Points>\n"
        << points << "</Points>\n<Cells>\n"
        << cells << "<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    const int type = per == 10 ? 24 : 10;  // VTK_QUADRATIC_TETRA : VTK_TETRA
    for (Eigen::Index c = 0; c < e; ++c) out << type << '\n';
    out << "</DataArray>\n</Cells>\n";
    if (!point_data.empty()) out << "<PointData>\n" << point_data << "</PointData>\n";
    out << "</Piece>\n</UnstructuredGrid>\n";
    data.write(out);
    out << "</VTKFile>\n";
    out.close();
    if (!out) throw InputError("cannot write '" + path + "'");
  });
}

}  // namespace vproto::ui_batch
