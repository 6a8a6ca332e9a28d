#pragma once
// Surface-mesh files through assimp: reading imports (STL, OBJ, PLY, OFF, 3MF, ...) and
// writing STL (binary) and OBJ, always to a temporary name renamed when complete.

#include <string>

#include "vproto/geometry/tri_mesh.h"

namespace vproto::ui_batch {

/// Reads every mesh in the file into one triangle mesh with coincident vertices welded.
/// Throws InputError naming the file when it cannot be read or holds no triangles.
geometry::TriMesh read_mesh(const std::string& path);

enum class MeshFormat { kStl, kObj };

/// Writes `mesh` (named `name` inside the file) atomically. Throws InputError when the
/// file cannot be written.
void write_mesh(const geometry::TriMesh& mesh, const std::string& name, MeshFormat format,
                const std::string& path);

}  // namespace vproto::ui_batch
