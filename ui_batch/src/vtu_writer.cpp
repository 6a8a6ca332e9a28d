#include "vproto/ui_batch/vtu_writer.h"

#include <cstdio>
#include <fstream>

#include "vproto/materials/errors.h"
#include "vproto/ui_batch/atomic_file.h"

namespace vproto::ui_batch {

void write_vtu(const geometry::TetMesh& mesh, const std::string& path,
               const Eigen::MatrixX3d& nodes, const std::vector<PointField>& fields) {
  const Eigen::MatrixX3d& x = nodes.rows() ? nodes : mesh.nodes;
  const Eigen::Index n = x.rows(), e = mesh.elements.rows(), per = mesh.elements.cols();
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp);
    out.precision(17);
    out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
           "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\""
        << n << "\" NumberOfCells=\"" << e << "\">\n";
    out << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
    for (Eigen::Index i = 0; i < n; ++i) out << x(i, 0) << ' ' << x(i, 1) << ' ' << x(i, 2) << '\n';
    out << "</DataArray>\n</Points>\n<Cells>\n"
           "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
    for (Eigen::Index c = 0; c < e; ++c) {
      for (Eigen::Index k = 0; k < per; ++k)
        out << mesh.elements(c, k) << (k + 1 < per ? ' ' : '\n');
    }
    out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
    for (Eigen::Index c = 0; c < e; ++c) out << (c + 1) * per << '\n';
    out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
    const int type = per == 10 ? 24 : 10;  // VTK_QUADRATIC_TETRA : VTK_TETRA
    for (Eigen::Index c = 0; c < e; ++c) out << type << '\n';
    out << "</DataArray>\n</Cells>\n";
    if (!fields.empty()) {
      out << "<PointData>\n";
      for (const auto& [name, values] : fields) {
        out << "<DataArray type=\"Float64\" Name=\"" << name << "\" NumberOfComponents=\""
            << values.cols() << "\" format=\"ascii\">\n";
        for (Eigen::Index i = 0; i < values.rows(); ++i) {
          for (Eigen::Index k = 0; k < values.cols(); ++k)
            out << values(i, k) << (k + 1 < values.cols() ? ' ' : '\n');
        }
        out << "</DataArray>\n";
      }
      out << "</PointData>\n";
    }
    out << "</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
    out.close();
    if (!out) throw InputError("cannot write '" + path + "'");
  });
}

}  // namespace vproto::ui_batch
