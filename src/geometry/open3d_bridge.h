#pragma once
// Conversions between u3d::Mesh and Open3D's TriangleMesh, for the stages that use Open3D's
// geometry processing (Poisson, decimation, smoothing, subdivision). Only geometry and vertex
// colours travel; the Open3D headers stay out of this header (they are slow to compile).
#include <memory>

#include "core/mesh.h"

namespace open3d::geometry {
class TriangleMesh;
}

namespace u3d {

std::shared_ptr<open3d::geometry::TriangleMesh> to_open3d(const Mesh& mesh);
Mesh from_open3d(const open3d::geometry::TriangleMesh& mesh);

}  // namespace u3d
