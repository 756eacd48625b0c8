#pragma once
// The static files of `unique3d serve`, compiled into the binary (cmake/web_assets.cmake): the page
// (web/index.html), the 3D viewer it loads (@google/model-viewer from npm, installed by the set-up), and
// the bundled example's view set, which the page offers to reconstruct. The page works offline: it
// loads nothing from anywhere but the server.
#include <string_view>
#include <vector>

namespace u3d::server {

struct WebAsset {
  std::string_view path;          // the URL path it is served at, "/" for the page
  std::string_view content_type;  // its Content-Type
  std::string_view data;
};

const std::vector<WebAsset>& web_assets();

// The asset served at `path`, or nullptr.
const WebAsset* find_web_asset(std::string_view path);

}  // namespace u3d::server
