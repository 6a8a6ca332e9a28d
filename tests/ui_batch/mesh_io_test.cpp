#include "vproto/ui_batch/mesh_io.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "vproto/geometry/csg.h"
#include "vproto/geometry/mass_properties.h"
#include "vproto/geometry/primitives.h"
#include "vproto/materials/errors.h"

namespace vproto::ui_batch {
namespace {

namespace fs = std::filesystem;

TEST(MeshIo, StlAndObjRoundTripThroughAssimp) {
  const fs::path dir = fs::temp_directory_path() / "vproto_mesh_io_test";
  fs::create_directories(dir);
  const geometry::TriMesh cyl = geometry::make_cylinder(2, 1, 0.5, 24, false);
  const double v = geometry::mass_properties(cyl).volume;
  for (MeshFormat f : {MeshFormat::kStl, MeshFormat::kObj}) {
    const fs::path file = dir / (f == MeshFormat::kStl ? "c.stl" : "c.obj");
    write_mesh(cyl, "c", f, file.string());
    ASSERT_TRUE(fs::exists(file));
    const geometry::TriMesh back = read_mesh(file.string());
    EXPECT_EQ(back.F.rows(), cyl.F.rows());
    EXPECT_EQ(back.V.rows(), cyl.V.rows());  // welded back to shared vertices
    EXPECT_EQ(geometry::solid_validation_error(back), "");
    EXPECT_NEAR(geometry::mass_properties(back).volume, v, 1e-6 * v);  // files hold floats
  }
  // nothing but the two files: no temporary or material files left behind
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir)) files += e.is_regular_file();
  EXPECT_EQ(files, 2);
  fs::remove_all(dir);
}

TEST(MeshIo, UnreadableFilesAreInputErrors) {
  EXPECT_THROW(read_mesh(VPROTO_TEST_DATA "/does_not_exist.stl"), InputError);
  const fs::path junk = fs::temp_directory_path() / "vproto_junk.stl";
  std::FILE* f = std::fopen(junk.c_str(), "w");
  std::fputs("this is not a mesh", f);
  std::fclose(f);
  EXPECT_THROW(read_mesh(junk.string()), InputError);
  fs::remove(junk);
  EXPECT_THROW(write_mesh(geometry::make_box({1, 1, 1}, false), "b", MeshFormat::kStl,
                          "/nonexistent_dir/b.stl"),
               InputError);
}

}  // namespace
}  // namespace vproto::ui_batch
