#include "server/job_inputs.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <map>
#include <mutex>

#include "core/error.h"
#include "core/image_decode.h"
#include "core/view_set.h"
#include "pipeline/generate.h"
#include "server/job.h"
#include "server/zip_archive.h"

namespace u3d::server {
namespace {

namespace fs = std::filesystem;

// One upload is decoded at a time, so that concurrent uploads of large images cannot take the memory
// of all their pixels at once.
std::mutex decode_mutex;

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

const unsigned char* bytes_of(const std::string& data) { return reinterpret_cast<const unsigned char*>(data.data()); }

// The image's size from its header within [min_side, max_side], then the whole image decoded once.
void check_image(const std::string& data, const std::string& name, int min_side, int max_side) {
  const ImageSize size = peek_image_size(bytes_of(data), data.size(), name);
  const std::string dims = std::to_string(size.width) + "x" + std::to_string(size.height);
  require(std::max(size.width, size.height) <= max_side,
          name + " is " + dims + ": larger than " + std::to_string(max_side) + " px per side");
  require(std::min(size.width, size.height) >= min_side,
          name + " is " + dims + ": smaller than " + std::to_string(min_side) + " px per side");
  decode_image(bytes_of(data), data.size(), name);
}

void write_file(const fs::path& path, const std::string& data) {
  std::ofstream out(path, std::ios::binary);
  out.write(data.data(), std::streamsize(data.size()));
  out.close();
  require(bool(out), "cannot write an uploaded file (is the jobs folder full?)");
}

bool is_zip(const UploadedFile& file) {
  return file.data.compare(0, 4, "PK\x03\x04") == 0 || file.data.compare(0, 4, "PK\x05\x06") == 0 ||
         lower(fs::path(file.filename).extension().string()) == ".zip";
}

std::string known_view_files() {
  std::string names;
  for (View v : kAllViews)
    for (bool normal : {false, true}) names += (names.empty() ? "" : ", ") + view_file_name(v, normal);
  return names;
}

}  // namespace

std::string view_file_for(const std::string& uploaded_name) {
  const size_t slash = uploaded_name.find_last_of("/\\");
  const std::string base = lower(slash == std::string::npos ? uploaded_name : uploaded_name.substr(slash + 1));
  for (View v : kAllViews)
    for (bool normal : {false, true})
      if (base == view_file_name(v, normal)) return base;
  return "";
}

void write_view_set_upload(const std::vector<UploadedFile>& files, const fs::path& dir, const UploadLimits& limits) {
  require(!files.empty(), "no view images: upload the eight PNGs of a view folder (" + known_view_files() +
                              "), or one zip of the folder");
  std::map<std::string, const std::string*> images;  // canonical name -> bytes
  std::vector<ZipEntry> unzipped;
  if (files.size() == 1 && is_zip(files[0])) {
    unzipped = read_zip(files[0].data, {64, limits.max_zip_bytes});
    for (const ZipEntry& entry : unzipped) {
      const std::string name = view_file_for(entry.name);
      if (name.empty()) continue;  // a README, thumbnails, the folder's other files
      require(images.emplace(name, &entry.data).second, "the zip holds " + name + " twice");
    }
  } else {
    for (const UploadedFile& file : files) {
      require(!is_zip(file), "a zip must be uploaded alone, without other files");
      const std::string name = view_file_for(file.filename);
      require(!name.empty(), "'" + file.filename + "' is not one of a view set's files (" + known_view_files() + ")");
      require(images.emplace(name, &file.data).second, name + " was uploaded twice");
    }
  }
  std::string missing;
  for (View v : kAllViews)
    for (bool normal : {false, true})
      if (!images.count(view_file_name(v, normal)))
        missing += (missing.empty() ? "" : ", ") + view_file_name(v, normal);
  require(missing.empty(), "the view set lacks " + missing);

  std::lock_guard lock(decode_mutex);
  for (const auto& [name, data] : images) {
    require(is_png_signature(bytes_of(*data), data->size()), name + " is not a PNG image");
    check_image(*data, name, 1, limits.max_view_side);
    write_file(dir / name, *data);
  }
  try {
    load_view_set(dir);
  } catch (const Error& e) {
    // The view set's own message names the files by their path in the job's folder: the client knows
    // them by their names alone.
    throw Error(without_folder(e.what(), dir));
  }
}

fs::path write_photo_upload(const UploadedFile& file, const fs::path& dir, const UploadLimits& limits) {
  const int max_side = limits.max_photo_side > 0 ? limits.max_photo_side : kMaxPhotoSide;
  const bool png = is_png_signature(bytes_of(file.data), file.data.size());
  require(png || is_jpeg_signature(bytes_of(file.data), file.data.size()),
          file.data.empty() ? "the photo is empty" : "the photo is not a PNG or JPEG image");
  {
    std::lock_guard lock(decode_mutex);
    check_image(file.data, "the photo", kMinPhotoSide, max_side);
  }
  const fs::path path = dir / (png ? "photo.png" : "photo.jpg");
  write_file(path, file.data);
  return path;
}

}  // namespace u3d::server
