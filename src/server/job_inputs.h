#pragma once
// What a client uploads to `unique3d serve`, checked and written into a job's input folder under the
// server's own names: the eight images of a view set (as files, or one zip of a view folder) or one
// photo. A client's file names only pick which of the known names a file is; they never become paths.
// Every image's size is read from its header before it is decoded (server::UploadLimits), so an image
// that claims a huge size is refused before its pixels are allocated, and every image is decoded once
// so that a broken one is refused at upload time rather than failing its job later.
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace u3d::server {

struct UploadedFile {
  std::string filename;  // as the client named it
  std::string data;
};

struct UploadLimits {
  int max_view_side = 4096;  // pixels per side of a view image
  int max_photo_side = 0;    // pixels per side of a photo (0: generate's own limit, pipeline/generate.h)
  size_t max_zip_bytes = 256u << 20;
};

// The canonical file name ("front_rgb.png", ...) that an uploaded name stands for, or "" when it is
// none: its last path part, compared without case.
std::string view_file_for(const std::string& uploaded_name);

// Writes the view set into `dir` (which must exist) as VIEWS_DIR/{view}_{rgb,normal}.png and checks
// that it loads as one (core/view_set.h). `files`: the eight PNGs, or one zip holding them (in any
// folder; other files in the zip are ignored). An Error saying what is wrong otherwise.
void write_view_set_upload(const std::vector<UploadedFile>& files, const std::filesystem::path& dir,
                           const UploadLimits& limits);

// Writes the photo (PNG or JPEG) into `dir` as photo.png or photo.jpg and returns its path; an Error
// when it is neither, is broken, or is too small or too large for generate.
std::filesystem::path write_photo_upload(const UploadedFile& file, const std::filesystem::path& dir,
                                         const UploadLimits& limits);

}  // namespace u3d::server
