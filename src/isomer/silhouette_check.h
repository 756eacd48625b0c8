#pragma once
// How well a reconstruction matches its input silhouettes: per view, the intersection over union of
// the mesh's rendered coverage and the view's mask (the normal map's, at its resolution).
#include <array>

#include "core/mesh.h"
#include "core/view_set.h"

namespace u3d {

std::array<float, 4> silhouette_iou(const Mesh& mesh, const ViewSet& views);

}  // namespace u3d
