#include "python/arrays.h"

#include <algorithm>
#include <cmath>

namespace py = pybind11;

namespace u3d::python {

namespace {

std::string shape_text(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

py::array read_only(py::array a) {
  a.attr("setflags")(py::arg("write") = false);
  return a;
}

}  // namespace

Image image_from_array(const py::handle& handle, const std::string& what, int min_channels, int max_channels) {
  if (!py::isinstance<py::array>(handle))
    throw py::type_error(what + ": expected a numpy array, got " +
                         std::string(py::str(handle.get_type().attr("__name__"))));
  const py::array a = py::reinterpret_borrow<py::array>(handle);
  const std::string channels = min_channels == max_channels
                                   ? std::to_string(min_channels)
                                   : std::to_string(min_channels) + " or " + std::to_string(max_channels);
  if (a.ndim() != 3 || a.shape(2) < min_channels || a.shape(2) > max_channels)
    throw py::value_error(what + ": expected an H x W x " + channels + " array, got shape " + shape_text(a));
  if (a.shape(0) == 0 || a.shape(1) == 0) throw py::value_error(what + ": the image is empty, shape " + shape_text(a));
  const bool u8 = py::isinstance<py::array_t<uint8_t>>(a);
  const bool f32 = py::isinstance<py::array_t<float>>(a);
  if (!u8 && !f32)
    throw py::value_error(what + ": expected dtype uint8 or float32, got " + std::string(py::str(a.dtype())));
  if (!(a.flags() & py::array::c_style))
    throw py::value_error(what + ": the array is not C-contiguous (numpy.ascontiguousarray makes a copy that is)");
  Image image(int(a.shape(1)), int(a.shape(0)), int(a.shape(2)));
  const size_t n = image.data.size();
  if (u8) {
    const uint8_t* p = static_cast<const uint8_t*>(a.data());
    const float scale = float(1.0 / 255.0);  // as the PNG/JPEG decoder scales 8-bit files (core/image_decode.cpp)
    for (size_t i = 0; i < n; ++i) image.data[i] = float(p[i]) * scale;
  } else {
    const float* p = static_cast<const float*>(a.data());
    for (size_t i = 0; i < n; ++i) {
      if (std::isnan(p[i])) throw py::value_error(what + ": contains NaN");
      if (!(p[i] >= 0.f && p[i] <= 1.f))
        throw py::value_error(what + ": float32 values must lie in [0, 1], found " + std::to_string(p[i]));
      image.data[i] = p[i];
    }
  }
  return image;
}

py::array_t<uint8_t> image_to_uint8(const Image& image, int channels) {
  channels = std::min(channels, image.channels);
  py::array_t<uint8_t> out({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(channels)});
  uint8_t* p = out.mutable_data();
  for (size_t i = 0; i < image.pixel_count(); ++i)
    for (int c = 0; c < channels; ++c) {
      const float v = std::clamp(image.data[i * image.channels + c], 0.f, 1.f);
      p[i * channels + c] = uint8_t(std::lround(v * 255.f));
    }
  return out;
}

py::array_t<float> image_to_float(const Image& image) {
  py::array_t<float> out({py::ssize_t(image.height), py::ssize_t(image.width), py::ssize_t(image.channels)});
  std::copy(image.data.begin(), image.data.end(), out.mutable_data());
  return out;
}

py::array float_rows(const float* data, size_t rows, size_t columns, py::handle owner) {
  return read_only(py::array_t<float>({py::ssize_t(rows), py::ssize_t(columns)},
                                      {py::ssize_t(columns * sizeof(float)), py::ssize_t(sizeof(float))}, data, owner));
}

py::array int_rows(const int* data, size_t rows, size_t columns, py::handle owner) {
  return read_only(py::array_t<int32_t>({py::ssize_t(rows), py::ssize_t(columns)},
                                        {py::ssize_t(columns * sizeof(int)), py::ssize_t(sizeof(int))}, data, owner));
}

std::string fspath(const py::handle& path) {
  if (!py::isinstance<py::str>(path) && !py::hasattr(path, "__fspath__"))
    throw py::type_error("expected a path (str or os.PathLike), got " +
                         std::string(py::str(path.get_type().attr("__name__"))));
  return py::str(py::module_::import("os").attr("fspath")(path));
}

}  // namespace u3d::python
