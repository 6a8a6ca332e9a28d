#pragma once
// The feature tree a script evaluates to: per body, CSG nodes over primitives whose
// transforms are already composed (a leaf carries its full placement).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "vproto/materials/errors.h"

namespace vproto::modeler {

struct Feature {
  enum class Kind {
    kBox,
    kCylinder,
    kSphere,
    kWedge,
    kPrism,
    kImport,
    kUnion,
    kDifference,
    kIntersection
  };
  Kind kind = Kind::kUnion;
  SourceLoc loc;

  // primitive parameters (SI)
  Eigen::Vector3d size = Eigen::Vector3d::Zero();           ///< box, wedge
  bool center = false;                                      ///< box, cylinder
  double height = 0;                                        ///< cylinder, prism
  double r1 = 0, r2 = 0;                                    ///< cylinder; r1 = radius for sphere
  int segments = 0;                                         ///< cylinder, sphere
  Eigen::MatrixX2d polygon;                                 ///< prism
  std::string path;                                         ///< import: absolute file path
  Eigen::Affine3d transform = Eigen::Affine3d::Identity();  ///< leaf placement

  std::vector<Feature> children;  ///< Boolean operands (difference: first minus the rest)

  bool is_leaf() const {
    return kind != Kind::kUnion && kind != Kind::kDifference && kind != Kind::kIntersection;
  }
};

/// Upper bound on the triangles a leaf will have before any Boolean (0 for imports).
long estimated_triangles(const Feature& leaf);

}  // namespace vproto::modeler
