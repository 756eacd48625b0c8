#pragma once
// numpy arrays in and out of the library's types: images (HxWxC uint8 or float32, C-contiguous) to
// core/image.h's float images with every problem a ValueError that names the array, and a mesh's
// attributes as read-only arrays that view the mesh's own memory (no copy) while the owner lives.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

#include "core/image.h"
#include "core/mesh.h"

namespace u3d::python {

// An HxWxC array (C from min_channels to max_channels), uint8 (0..255, scaled exactly as an 8-bit file
// is decoded) or float32 (finite, in [0, 1]), C-contiguous, to an Image in [0, 1]. ValueError (TypeError
// for what is not an array) naming `what` otherwise.
Image image_from_array(const pybind11::handle& array, const std::string& what, int min_channels, int max_channels);

// An Image as an HxWxC uint8 array (values rounded from [0, 1]; a copy). `channels` < image.channels
// drops the last ones (alpha).
pybind11::array_t<uint8_t> image_to_uint8(const Image& image, int channels);

// An Image as an HxWxC float32 array (a copy).
pybind11::array_t<float> image_to_float(const Image& image);

// Read-only N x `columns` views of a mesh attribute owned by `owner` (kept alive by the array).
pybind11::array float_rows(const float* data, size_t rows, size_t columns, pybind11::handle owner);
pybind11::array int_rows(const int* data, size_t rows, size_t columns, pybind11::handle owner);

// os.fspath(path) as a filesystem path; TypeError for anything else.
std::string fspath(const pybind11::handle& path);

}  // namespace u3d::python
