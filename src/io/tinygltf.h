#pragma once
// The one way unique3d includes tinygltf: every translation unit must see the same configuration.
// Images are decoded with OpenCV through our own loader callback, so tinygltf's bundled stb is off.
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#include <tiny_gltf.h>
