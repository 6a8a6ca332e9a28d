#pragma once
// VTK XML unstructured grids (ParaView's .vtu) of tetrahedral meshes, written atomically.

#include <string>
#include <utility>
#include <vector>

#include "vproto/geometry/tet_mesh.h"

namespace vproto::ui_batch {

/// Point data: a name and #N by 1 (scalar) or #N by 3 (vector) values.
using PointField = std::pair<std::string, Eigen::MatrixXd>;

/// Writes `mesh` (VTK tetra or quadratic tetra) at `nodes` (#N by 3; the mesh's own nodes
/// when empty) with optional point data. Throws InputError when the file cannot be written.
void write_vtu(const geometry::TetMesh& mesh, const std::string& path,
               const Eigen::MatrixX3d& nodes = {}, const std::vector<PointField>& fields = {});

}  // namespace vproto::ui_batch
