// The Python module `unique3d` (docs/python.md): the library's facade (src/pipeline) with numpy arrays
// in and out. Every run releases the GIL and reports to a PythonProgress (python/python_progress.h),
// through which a callback, a CancelToken or Ctrl-C stops it; u3d::Error becomes unique3d.Error with the
// same message, bad arguments ValueError or TypeError.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <random>
#include <string>

#include "core/error.h"
#include "core/memory.h"
#include "core/parallel.h"
#include "core/view_set.h"
#include "eval/eval_report.h"
#include "eval/evaluate.h"
#include "io/mesh_io.h"
#include "nn/runtime.h"
#include "pipeline/doctor.h"
#include "pipeline/generate.h"
#include "pipeline/reconstruct.h"
#include "pipeline/summary_json.h"
#include "python/arrays.h"
#include "python/python_progress.h"
#include "render/render_view.h"
#include "unique3d/version.h"

namespace py = pybind11;

namespace u3d::python {
namespace {

// A mesh and the summary of the run that made it (JSON text, as pipeline/summary_json.h writes it).
struct PyMesh {
  Mesh mesh;
  std::string summary;
};
static_assert(sizeof(Vec3f) == 3 * sizeof(float) && sizeof(Vec2f) == 2 * sizeof(float) &&
              sizeof(Vec3i) == 3 * sizeof(int));

py::object json_to_python(const std::string& text) {
  if (text.empty()) return py::none();
  return py::module_::import("json").attr("loads")(text);
}

TextureFormat texture_format_argument(const std::string& text) {
  if (text == "png") return TextureFormat::Png;
  if (text == "jpg") return TextureFormat::Jpeg;
  throw py::value_error("texture_format must be \"png\" or \"jpg\", got \"" + text + "\"");
}

NormalSpace normal_space_argument(const std::string& text) {
  if (text == "world") return NormalSpace::World;
  if (text == "camera") return NormalSpace::Camera;
  throw py::value_error("normal_space must be \"world\" or \"camera\", got \"" + text + "\"");
}

int int_in_range(const py::object& value, const char* name, long long lo, long long hi) {
  if (!py::isinstance<py::int_>(value) || py::isinstance<py::bool_>(value))
    throw py::type_error(std::string(name) + " must be an int, got " +
                         std::string(py::str(value.get_type().attr("__name__"))));
  const long long v = value.cast<long long>();
  if (v < lo || v > hi)
    throw py::value_error(std::string(name) + " must be in [" + std::to_string(lo) + ", " + std::to_string(hi) +
                          "], got " + std::to_string(v));
  return int(v);
}

// The arguments that shape the output mesh, as `unique3d reconstruct` and `generate` take them
// (cli/mesh_output_options.h): the same ranges, and the texture options only with a texture.
struct MeshOptions {
  py::object faces = py::none();
  std::string colour = "texture";
  py::object texture_size = py::none();
  std::string texture_format = "png";
  py::object coarse_steps = py::none();
  py::object refine_steps = py::none();
  bool silhouette_fit = true;
};

void apply_mesh_options(const MeshOptions& m, ReconstructOptions& o, TextureFormat& format) {
  if (m.colour != "texture" && m.colour != "vertex")
    throw py::value_error("colour must be \"texture\" or \"vertex\", got \"" + m.colour + "\"");
  o.color_mode = m.colour == "texture" ? ColorMode::Texture : ColorMode::Vertex;
  if (!m.faces.is_none()) o.faces = size_t(int_in_range(m.faces, "faces", 100, 100000000));
  if (!m.texture_size.is_none()) {
    if (o.color_mode != ColorMode::Texture) throw py::value_error("texture_size needs colour=\"texture\"");
    o.texture.atlas.texture_size = int_in_range(m.texture_size, "texture_size", 64, 8192);
  }
  if (m.texture_format != "png" && o.color_mode != ColorMode::Texture)
    throw py::value_error("texture_format needs colour=\"texture\"");
  format = texture_format_argument(m.texture_format);
  if (!m.coarse_steps.is_none()) o.coarse.steps = int_in_range(m.coarse_steps, "coarse_steps", 0, 100000);
  if (!m.refine_steps.is_none()) o.refine.steps = int_in_range(m.refine_steps, "refine_steps", 0, 100000);
  o.silhouette_fit.enabled = m.silhouette_fit;
}

std::shared_ptr<CancelToken> token_argument(const py::object& cancel) {
  if (cancel.is_none()) return nullptr;
  if (!py::isinstance<CancelToken>(cancel))
    throw py::type_error("cancel must be a unique3d.CancelToken, got " +
                         std::string(py::str(cancel.get_type().attr("__name__"))));
  return cancel.cast<std::shared_ptr<CancelToken>>();
}

py::object progress_argument(const py::object& progress) {
  if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
    throw py::type_error("progress must be a callable taking a unique3d.ProgressEvent, or None");
  return progress;
}

// Runs `work` with the GIL released and `listener` as the thread's listener; what Python raised in the
// listener (the callback, Ctrl-C) comes back in place of the facade's Cancelled, and also when the run
// finished before it noticed.
template <class Work>
auto run_released(PythonProgress& listener, Work&& work) {
  try {
    auto result = [&] {
      py::gil_scoped_release release;
      ProgressScope scope(&listener);
      return work();
    }();
    listener.rethrow_python_error();
    return result;
  } catch (const Cancelled&) {
    listener.rethrow_python_error();
    throw;
  }
}

std::array<std::string, 4> view_names(const char* kind) {
  std::array<std::string, 4> names;
  for (View v : kAllViews)
    names[size_t(v)] = std::string(kind) + "[" + std::to_string(int(v)) + "] (" + view_name(v) + ")";
  return names;
}

std::array<Image, 4> four_images(const py::object& list, const char* kind) {
  if (!py::isinstance<py::sequence>(list) || py::isinstance<py::str>(list))
    throw py::type_error(std::string(kind) + " must be a sequence of four arrays (front, right, back, left)");
  const py::sequence seq = py::reinterpret_borrow<py::sequence>(list);
  if (seq.size() != 4)
    throw py::value_error(std::string(kind) + " must hold four arrays (front, right, back, left), got " +
                          std::to_string(seq.size()));
  const std::array<std::string, 4> names = view_names(kind);
  std::array<Image, 4> images;
  for (size_t i = 0; i < 4; ++i) images[i] = image_from_array(seq[i], names[i], 3, 4);
  return images;
}

std::shared_ptr<PyMesh> mesh_result(ReconstructSummary summary) {
  auto out = std::make_shared<PyMesh>();
  out->summary = summary_json(summary).dump();
  out->mesh = std::move(summary.mesh);
  return out;
}

py::object reconstruct(const py::object& views, const py::object& output, const MeshOptions& mesh_options,
                       const py::object& normal_space, bool previews, bool official_scale, const py::object& progress,
                       const py::object& cancel) {
  ReconstructRequest request;
  apply_mesh_options(mesh_options, request.options, request.texture_format);
  if (!output.is_none()) request.output = fspath(output);
  request.previews = previews;
  request.official_output_scale = official_scale;
  PythonProgress listener(progress_argument(progress), token_argument(cancel));
  std::shared_ptr<ViewSet> view_set;
  if (py::isinstance<ViewSet>(views)) {
    if (!normal_space.is_none())
      throw py::value_error("normal_space is for a views folder; a ViewSet has its own (ViewSet(..., normal_space=))");
    view_set = views.cast<std::shared_ptr<ViewSet>>();
  } else {
    request.views_dir = fspath(views);
    if (!normal_space.is_none()) request.normal_space = normal_space_argument(normal_space.cast<std::string>());
  }
  ReconstructSummary summary = run_released(
      listener, [&] { return view_set ? reconstruct_view_set(*view_set, request) : reconstruct_folder(request); });
  return py::cast(mesh_result(std::move(summary)));
}

// A folder made for one run and removed with everything in it when the run is over.
class TemporaryFolder {
 public:
  TemporaryFolder() {
    std::random_device device;
    path_ = std::filesystem::temp_directory_path() /
            ("unique3d-python-" + std::to_string(device()) + std::to_string(device()));
    std::filesystem::create_directories(path_);
  }
  ~TemporaryFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// `unique3d.Result` of generate: the mesh, the intermediates as arrays, the summary.
struct GenerateResult {
  py::object mesh;
  py::dict intermediates;
  py::object summary;
};

// Every PNG under `folder` as {"views/front_rgb": array, ...} (paths relative, without the extension).
py::dict read_intermediates(const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(folder))
    if (entry.is_regular_file() && entry.path().extension() == ".png" && entry.path().filename().string()[0] != '.')
      files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  py::dict out;
  for (const std::filesystem::path& file : files) {
    Image image;
    {
      py::gil_scoped_release release;
      image = load_image(file);
    }
    std::filesystem::path key = std::filesystem::relative(file, folder);
    key.replace_extension();
    out[py::str(key.generic_string())] = image_to_float(image);
  }
  return out;
}

// The photo argument of generate: a path, or an image array (numpy, or anything numpy.asarray takes,
// such as a PIL image) written losslessly into `scratch` for the facade to read.
// A PIL image in a mode other than RGB or RGBA (grey, palette, 16-bit grey, ...) converted to RGBA when
// it has transparency and to RGB when not; anything else as it is.
py::object pil_as_rgb_or_rgba(const py::object& image) {
  if (!py::hasattr(image, "mode") || !py::hasattr(image, "convert") || !py::hasattr(image, "info")) return image;
  const std::string mode = py::str(image.attr("mode"));
  if (mode == "RGB" || mode == "RGBA") return image;
  const bool alpha = mode.find('A') != std::string::npos || mode.find('a') != std::string::npos ||
                     image.attr("info").contains("transparency");
  return image.attr("convert")(alpha ? "RGBA" : "RGB");
}

std::filesystem::path photo_argument(const py::object& image, const TemporaryFolder& scratch) {
  if (py::isinstance<py::str>(image) || py::hasattr(image, "__fspath__")) return fspath(image);
  py::object array = image;
  if (!py::isinstance<py::array>(image)) {
    if (!py::hasattr(image, "__array_interface__") && !py::hasattr(image, "__array__"))
      throw py::type_error("image must be a path, a numpy array or a PIL image, got " +
                           std::string(py::str(image.get_type().attr("__name__"))));
    array = py::module_::import("numpy").attr("ascontiguousarray")(pil_as_rgb_or_rgba(image));
  }
  const bool eight_bit = py::isinstance<py::array_t<uint8_t>>(array);
  const Image photo = image_from_array(array, "image", 3, 4);
  const std::filesystem::path path = scratch.path() / "photo.png";
  py::gil_scoped_release release;
  save_image(photo, path, eight_bit ? 8 : 16);
  return path;
}

std::optional<nn::Precision> dtype_argument(const py::object& dtype) {
  if (dtype.is_none()) return std::nullopt;
  const std::string text = py::str(dtype);
  if (text == "auto") return std::nullopt;
  if (text != "fp32" && text != "bf16" && text != "fp16")
    throw py::value_error("dtype must be \"auto\", \"fp32\", \"bf16\" or \"fp16\", got \"" + text + "\"");
  return nn::parse_precision(text, "dtype");
}

struct GenerateArguments {
  py::object image, models, output, seed, steps, dtype, keep_intermediates, from_intermediates;
  bool refine = true, raw_matte = false;
  py::object multiview_size, refine_size, normal_size;
  bool official_scale = false;
  MeshOptions mesh;
  py::object progress, cancel;
};

GenerateResult generate_mesh(const GenerateArguments& a) {
  GenerateRequest request;
  request.network.models = fspath(a.models);
  if (!a.seed.is_none()) {
    if (!py::isinstance<py::int_>(a.seed) || a.seed.cast<long long>() < 0)
      throw py::value_error("seed must be an int >= 0");
    request.network.seed = a.seed.cast<uint64_t>();
  }
  request.network.precision = dtype_argument(a.dtype);
  if (!a.steps.is_none()) request.multiview.steps = request.normals.steps = int_in_range(a.steps, "steps", 1, 1000);
  if (!a.multiview_size.is_none()) request.multiview.size = int_in_range(a.multiview_size, "multiview_size", 16, 4096);
  if (!a.refine_size.is_none()) request.refine_options.size = int_in_range(a.refine_size, "refine_size", 32, 8192);
  if (!a.normal_size.is_none()) request.normals.size = int_in_range(a.normal_size, "normal_size", 16, 4096);
  request.refine = a.refine;
  request.raw_matte = a.raw_matte;
  request.official_output_scale = a.official_scale;
  apply_mesh_options(a.mesh, request.reconstruct, request.texture_format);
  if (!a.output.is_none()) request.output = fspath(a.output);
  if (!a.from_intermediates.is_none()) request.from_intermediates = fspath(a.from_intermediates);
  TemporaryFolder scratch;
  if (!a.image.is_none()) request.image = photo_argument(a.image, scratch);
  const bool keep = !a.keep_intermediates.is_none() &&
                    !(py::isinstance<py::bool_>(a.keep_intermediates) && !a.keep_intermediates.cast<bool>());
  if (keep)
    request.keep_intermediates = py::isinstance<py::bool_>(a.keep_intermediates)
                                     ? scratch.path() / "intermediates"
                                     : std::filesystem::path(fspath(a.keep_intermediates));
  PythonProgress listener(progress_argument(a.progress), token_argument(a.cancel));
  GenerateSummary summary = run_released(listener, [&] { return generate(request, nullptr); });
  GenerateResult result;
  result.summary = json_to_python(summary_json(summary).dump());
  auto mesh = std::make_shared<PyMesh>();
  mesh->summary = summary_json(summary.reconstruction).dump();
  mesh->mesh = std::move(summary.reconstruction.mesh);
  result.mesh = py::cast(mesh);
  if (keep) result.intermediates = read_intermediates(request.keep_intermediates);
  return result;
}

// A Mesh argument: a unique3d.Mesh, or a mesh file's path.
Mesh mesh_argument(const py::object& mesh) {
  if (py::isinstance<PyMesh>(mesh)) return mesh.cast<const PyMesh&>().mesh;
  const std::string path = fspath(mesh);
  py::gil_scoped_release release;
  return read_mesh(path);
}

py::dict doctor_dict(const DoctorReport& r) {
  py::dict system;
  system["cpu"] = r.system.cpu;
  system["cores"] = r.system.cores;
  system["threads"] = r.system.threads;
  system["avx512"] = r.system.avx512;
  system["avx512_bf16"] = r.system.avx512_bf16;
  system["default_precision"] = r.system.default_precision;
  system["torch_version"] = r.system.torch_version;
  system["onednn"] = r.system.onednn;
  system["blas"] = r.system.blas;
  system["cuda"] = r.system.cuda;
  py::list networks;
  for (const NetworkCheckResult& n : r.networks) {
    py::dict d;
    d["name"] = network_name(n.network);
    d["used_by"] = network_users(n.network);
    d["ok"] = n.ok();
    d["error"] = n.error;
    d["seconds"] = n.seconds;
    networks.append(d);
  }
  py::dict out;
  out["system"] = system;
  out["models"] = r.models.string();
  out["networks"] = networks;
  out["generate_ready"] = r.generate_ready();
  out["generate_without_refine_ready"] = r.generate_without_refine_ready();
  return out;
}

}  // namespace
}  // namespace u3d::python

PYBIND11_MODULE(unique3d, m) {
  using namespace u3d;
  using namespace u3d::python;
  m.doc() = "Unique3D: one photo to a textured 3D mesh (ISOMER reconstruction, diffusion networks on libtorch).";
  m.attr("__version__") = UNIQUE3D_VERSION;
  set_progress_quiet(true);
  // The run-time set-up of the command (cli/main.cpp): the same kernels, threads and allocator, so that a
  // run gives the command's numbers bit for bit. UNIQUE3D_THREADS sets the thread count, as for the command.
  keep_freed_memory_for_reuse();
  configure_threads();
  nn::configure_torch_threads();

  // The exception types live as long as the module (its attributes hold them).
  static PyObject* error_type = PyErr_NewExceptionWithDoc(
      "unique3d.Error",
      "A failure of the library: bad files, bad data, a model folder that cannot run (the CLI's message).", nullptr,
      nullptr);
  static PyObject* cancelled_type = PyErr_NewExceptionWithDoc(
      "unique3d.Cancelled", "The run was stopped by CancelToken.cancel().", error_type, nullptr);
  m.add_object("Error", py::handle(error_type));
  m.add_object("Cancelled", py::handle(cancelled_type));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Cancelled& e) {
      PyErr_SetString(cancelled_type, e.what());
    } catch (const Error& e) {
      PyErr_SetString(error_type, e.what());
    }
  });

  py::class_<CancelToken, std::shared_ptr<CancelToken>>(
      m, "CancelToken", "Pass as cancel= to a run; cancel() from any thread stops it at its next check.")
      .def(py::init<>())
      .def("cancel", &CancelToken::cancel, "Ask the runs holding this token to stop (unique3d.Cancelled).")
      .def_property_readonly("cancelled", &CancelToken::cancelled);

  py::class_<PythonEvent>(m, "ProgressEvent", "One progress event of a run, as the progress= callable gets it.")
      .def_readonly("kind", &PythonEvent::kind, "\"stage_begin\", \"stage_end\", \"message\" or \"step\"")
      .def_readonly("text", &PythonEvent::text, "The stage's name, or the message")
      .def_readonly("seconds", &PythonEvent::seconds, "stage_end: the stage's time in seconds")
      .def_readonly("step", &PythonEvent::step, "step: the 1-based step of `steps`")
      .def_readonly("steps", &PythonEvent::steps)
      .def_readonly("seconds_left", &PythonEvent::seconds_left, "step: the loop's time left, estimated")
      .def("__repr__", [](const PythonEvent& e) {
        std::string s = "ProgressEvent(" + e.kind + ", '" + e.text + "'";
        if (e.kind == "step") s += ", " + std::to_string(e.step) + "/" + std::to_string(e.steps);
        if (e.kind == "stage_end") s += ", " + std::to_string(e.seconds) + " s";
        return s + ")";
      });

  py::class_<ViewSet, std::shared_ptr<ViewSet>>(
      m, "ViewSet",
      "The four views (front, right, back, left) ISOMER reconstructs from: an RGB(A) image and a normal map "
      "each, checked like a views folder.")
      .def(py::init([](const py::object& rgb, const py::object& normals, const std::string& normal_space) {
             std::array<Image, 4> rgb_images = four_images(rgb, "rgb");
             std::array<Image, 4> normal_images = four_images(normals, "normals");
             const NormalSpace space = normal_space_argument(normal_space);
             return std::make_shared<ViewSet>(make_view_set(std::move(rgb_images), std::move(normal_images), space,
                                                            view_names("rgb"), view_names("normals")));
           }),
           py::arg("rgb"), py::arg("normals"), py::kw_only(), py::arg("normal_space") = "world")
      .def_static(
          "load",
          [](const py::object& folder, const std::string& normal_space) {
            const std::string dir = fspath(folder);
            const NormalSpace space = normal_space_argument(normal_space);
            py::gil_scoped_release release;
            return std::make_shared<ViewSet>(load_view_set(dir, space));
          },
          py::arg("folder"), py::kw_only(), py::arg("normal_space") = "world",
          "Loads a views folder ({front,right,back,left}_{rgb,normal}.png).")
      .def_property_readonly("rgb_resolution", &ViewSet::rgb_resolution)
      .def_property_readonly("normal_resolution", &ViewSet::normal_resolution)
      .def_property_readonly(
          "rgb",
          [](const ViewSet& s) {
            py::list out;
            for (const ViewImages& v : s.views) out.append(image_to_float(v.rgb));
            return out;
          },
          "The four RGBA images (float32 in [0, 1], alpha = mask), a copy.")
      .def_property_readonly(
          "normals",
          [](const ViewSet& s) {
            py::list out;
            for (const ViewImages& v : s.views) out.append(image_to_float(v.normals));
            return out;
          },
          "The four normal maps decoded to world-space unit vectors (x, y, z, mask), float32, a copy.");

  py::class_<PyMesh, std::shared_ptr<PyMesh>>(m, "Mesh", "A triangle mesh with its colours (a texture or per vertex).")
      .def_property_readonly(
          "vertices",
          [](py::object self) {
            const Mesh& mesh = self.cast<const PyMesh&>().mesh;
            return float_rows(mesh.positions.empty() ? nullptr : mesh.positions[0].data(), mesh.positions.size(), 3,
                              self);
          },
          "N x 3 float32, read-only, a view of the mesh's memory.")
      .def_property_readonly(
          "faces",
          [](py::object self) {
            const Mesh& mesh = self.cast<const PyMesh&>().mesh;
            return int_rows(mesh.faces.empty() ? nullptr : mesh.faces[0].data(), mesh.faces.size(), 3, self);
          },
          "M x 3 int32 vertex indices, counter-clockwise seen from outside, read-only.")
      .def_property_readonly(
          "uv",
          [](py::object self) -> py::object {
            const Mesh& mesh = self.cast<const PyMesh&>().mesh;
            if (!mesh.has_uvs()) return py::none();
            return float_rows(mesh.uvs[0].data(), mesh.uvs.size(), 2, self);
          },
          "N x 2 float32 texture coordinates ((0, 0) = the texture's bottom-left), or None; read-only.")
      .def_property_readonly(
          "vertex_colors",
          [](py::object self) -> py::object {
            const Mesh& mesh = self.cast<const PyMesh&>().mesh;
            if (!mesh.has_colors()) return py::none();
            return float_rows(mesh.colors[0].data(), mesh.colors.size(), 3, self);
          },
          "N x 3 float32 sRGB colours in [0, 1], or None; read-only.")
      .def_property_readonly(
          "texture",
          [](const PyMesh& self) -> py::object {
            if (!self.mesh.has_texture()) return py::none();
            return image_to_uint8(self.mesh.materials[0].texture, 3);
          },
          "H x W x 3 uint8 sRGB texture (row 0 at the top), or None; a new array each time.")
      .def_property_readonly(
          "summary", [](const PyMesh& self) { return json_to_python(self.summary); },
          "The run's summary (topology, colouring, texture, silhouette IoU, timings) as a dict, or None.")
      .def(
          "save",
          [](const PyMesh& self, const py::object& path, const std::string& texture_format) {
            const std::string out = fspath(path);
            const TextureFormat format = texture_format_argument(texture_format);
            py::gil_scoped_release release;
            check_mesh_output(out);
            write_mesh(self.mesh, out, {format});
          },
          py::arg("path"), py::kw_only(), py::arg("texture_format") = "png",
          "Writes the mesh as GLB, OBJ or PLY by the extension (atomically).")
      .def("__repr__", [](const PyMesh& self) {
        return "<unique3d.Mesh " + std::to_string(self.mesh.vertex_count()) + " vertices, " +
               std::to_string(self.mesh.face_count()) + " faces" + (self.mesh.has_texture() ? ", textured" : "") + ">";
      });

  py::class_<GenerateResult>(m, "Result", "What generate made: the mesh, the intermediates, the summary.")
      .def_readonly("mesh", &GenerateResult::mesh)
      .def_readonly("intermediates", &GenerateResult::intermediates,
                    "With keep_intermediates: every stage's images, {\"views/front_normal\": float32 array, ...}")
      .def_readonly("summary", &GenerateResult::summary, "Per stage: seconds, peak memory; the mesh's summary");

  m.def(
      "generate",
      [](const py::object& image, const py::object& models, const py::object& output, const py::object& seed,
         const py::object& steps, const py::object& dtype, bool refine, bool raw_matte,
         const py::object& keep_intermediates, const py::object& from_intermediates, const py::object& multiview_size,
         const py::object& refine_size, const py::object& normal_size, const py::object& faces,
         const std::string& colour, const py::object& texture_size, const std::string& texture_format,
         const py::object& coarse_steps, const py::object& refine_steps, bool silhouette_fit, bool official_scale,
         const py::object& progress, const py::object& cancel) {
        GenerateArguments a;
        a.mesh.silhouette_fit = silhouette_fit;
        a.image = image, a.models = models, a.output = output, a.seed = seed, a.steps = steps, a.dtype = dtype;
        a.refine = refine, a.raw_matte = raw_matte, a.keep_intermediates = keep_intermediates,
        a.from_intermediates = from_intermediates;
        a.multiview_size = multiview_size, a.refine_size = refine_size, a.normal_size = normal_size;
        a.mesh.faces = faces, a.mesh.colour = colour, a.mesh.texture_size = texture_size;
        a.mesh.texture_format = texture_format, a.mesh.coarse_steps = coarse_steps, a.mesh.refine_steps = refine_steps;
        a.official_scale = official_scale, a.progress = progress, a.cancel = cancel;
        return generate_mesh(a);
      },
      py::arg("image"), py::kw_only(), py::arg("models"), py::arg("output") = py::none(), py::arg("seed") = py::none(),
      py::arg("steps") = py::none(), py::arg("dtype") = py::none(), py::arg("refine") = true,
      py::arg("raw_matte") = false, py::arg("keep_intermediates") = py::none(),
      py::arg("from_intermediates") = py::none(), py::arg("multiview_size") = py::none(),
      py::arg("refine_size") = py::none(), py::arg("normal_size") = py::none(), py::arg("faces") = py::none(),
      py::arg("colour") = "texture", py::arg("texture_size") = py::none(), py::arg("texture_format") = "png",
      py::arg("coarse_steps") = py::none(), py::arg("refine_steps") = py::none(), py::arg("silhouette_fit") = true,
      py::arg("official_scale") = false, py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
      "The whole method, as `unique3d generate`: a photo (path, numpy array or PIL image) to a mesh.");

  m.def(
      "load_mesh",
      [](const py::object& path) {
        auto out = std::make_shared<PyMesh>();
        out->mesh = mesh_argument(path);
        return out;
      },
      py::arg("path"), "Reads a GLB, glTF, OBJ or PLY file.");

  m.def(
      "evaluate",
      [](const py::object& pred, const py::object& gt, bool normalize, bool appearance, int surface_samples,
         uint64_t seed) {
        EvalOptions o;
        o.normalize = normalize;
        o.appearance = appearance;
        if (surface_samples < 1000) throw py::value_error("surface_samples must be at least 1000");
        o.surface_samples = size_t(surface_samples);
        o.seed = seed;
        Mesh p = mesh_argument(pred), g = mesh_argument(gt);
        std::string json;
        {
          py::gil_scoped_release release;
          json = report_to_json(evaluate_meshes(std::move(p), std::move(g), o)).dump();
        }
        return json_to_python(json);
      },
      py::arg("pred"), py::arg("gt"), py::kw_only(), py::arg("normalize") = true, py::arg("appearance") = true,
      py::arg("surface_samples") = 100000, py::arg("seed") = 0,
      "Metrics of a predicted mesh against ground truth (Mesh or path each), as `unique3d eval --json`.");

  m.def(
      "doctor",
      [](const py::object& models, bool load) {
        const std::string folder = fspath(models);
        DoctorReport report;
        {
          py::gil_scoped_release release;
          report = run_doctor(folder, load ? NetworkCheck::kLoad : NetworkCheck::kShapes);
        }
        return doctor_dict(report);
      },
      py::arg("models"), py::kw_only(), py::arg("load") = false,
      "The machine and every network of a model folder, as `unique3d doctor` reports them.");

  m.def(
      "render",
      [](const py::object& mesh_or_path, int resolution, int ssaa, const std::string& normal_space, bool flat,
         bool normalize, float fill) {
        Mesh mesh = mesh_argument(mesh_or_path);
        if (resolution < 1 || resolution > 8192) throw py::value_error("resolution must be in [1, 8192]");
        if (ssaa < 1 || resolution * ssaa > 8192)
          throw py::value_error("ssaa must be at least 1 and resolution x ssaa at most 8192, got " +
                                std::to_string(ssaa));
        if (!(fill > 0.f && fill <= 1.f)) throw py::value_error("fill must be in (0, 1]");
        RenderSettings settings;
        settings.normal_space = normal_space_argument(normal_space);
        settings.smooth_normals = !flat;
        settings.ssaa = ssaa;
        std::array<RenderedView, 4> views;
        {
          py::gil_scoped_release release;
          if (normalize) normalize_to_unit_box(mesh, fill);
          for (View v : kAllViews) views[size_t(v)] = render_view(mesh, view_camera(v, resolution), settings);
        }
        py::dict out;
        for (View v : kAllViews) {
          out[py::str(std::string(view_name(v)) + "_rgb")] = image_to_float(views[size_t(v)].rgb);
          out[py::str(std::string(view_name(v)) + "_normal")] = image_to_float(views[size_t(v)].normal);
        }
        return out;
      },
      py::arg("mesh"), py::kw_only(), py::arg("resolution") = 512, py::arg("ssaa") = 2,
      py::arg("normal_space") = "world", py::arg("flat") = false, py::arg("normalize") = true, py::arg("fill") = 0.9f,
      "The four canonical views of a mesh (Mesh or path), as `unique3d render` draws them: {\"front_rgb\": "
      "H x W x 4 float32, \"front_normal\": ..., ...}.");

  m.def(
      "read_image",
      [](const py::object& path) {
        const std::string file = fspath(path);
        Image image;
        {
          py::gil_scoped_release release;
          image = load_image(file);
        }
        return image_to_float(image);
      },
      py::arg("path"),
      "A PNG or JPEG file as an H x W x C float32 array in [0, 1] (C = 1, 3 or 4), as the library reads it.");

  m.def(
      "reconstruct",
      [](const py::object& views, const py::object& output, const py::object& faces, const std::string& colour,
         const py::object& texture_size, const std::string& texture_format, const py::object& coarse_steps,
         const py::object& refine_steps, bool silhouette_fit, const py::object& normal_space, bool previews,
         bool official_scale, const py::object& progress, const py::object& cancel) {
        MeshOptions o;
        o.silhouette_fit = silhouette_fit;
        o.faces = faces;
        o.colour = colour;
        o.texture_size = texture_size;
        o.texture_format = texture_format;
        o.coarse_steps = coarse_steps;
        o.refine_steps = refine_steps;
        return reconstruct(views, output, o, normal_space, previews, official_scale, progress, cancel);
      },
      py::arg("views"), py::kw_only(), py::arg("output") = py::none(), py::arg("faces") = py::none(),
      py::arg("colour") = "texture", py::arg("texture_size") = py::none(), py::arg("texture_format") = "png",
      py::arg("coarse_steps") = py::none(), py::arg("refine_steps") = py::none(), py::arg("silhouette_fit") = true,
      py::arg("normal_space") = py::none(), py::arg("previews") = false, py::arg("official_scale") = false,
      py::arg("progress") = py::none(), py::arg("cancel") = py::none(),
      "ISOMER: a mesh from four views (a views folder or a ViewSet), as `unique3d reconstruct`. With output= "
      "the facade also writes the mesh file (after everything else succeeded).");
}
