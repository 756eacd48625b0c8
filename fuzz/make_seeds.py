#!/usr/bin/env python3
# Writes the small hand-made seed inputs of fuzz/corpus/<target>/ (committed; rerun after changing this
# file). Larger seeds come from tests/data and examples, which scripts/fuzz.sh links in by path. Only the
# standard library is used, so the seeds are the same on every machine.
import base64
import collections
import json
import os
import pickle
import struct
import sys
import types
import zlib

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus")


def put(target, name, data):
    os.makedirs(os.path.join(root, target), exist_ok=True)
    with open(os.path.join(root, target, name), "wb") as f:
        f.write(data.encode() if isinstance(data, str) else data)


# ---- images: tiny PNGs of every colour type and bit depth OpenCV reads
def png(width, height, color_type, bit_depth, rows, palette=None):
    def chunk(kind, body):
        return struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
    out = b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, bit_depth, color_type, 0, 0, 0))
    if palette:
        out += chunk(b"PLTE", palette)
    out += chunk(b"IDAT", zlib.compress(b"".join(b"\x00" + r for r in rows)))
    return out + chunk(b"IEND", b"")


channels = {0: 1, 2: 3, 3: 1, 4: 2, 6: 4}
for color_type, depth in [(0, 8), (0, 16), (2, 8), (2, 16), (3, 8), (4, 8), (6, 8), (6, 16)]:
    w, h = 3, 2
    bpp = channels[color_type] * depth // 8
    rows = [bytes((x * 40 + y * 90 + k * 17) % 256 for x in range(w * bpp) for k in [0]) for y in range(h)]
    pal = bytes(range(0, 48)) if color_type == 3 else None
    if color_type == 3:
        rows = [bytes([0, 5, 15]), bytes([1, 2, 3])]
    put("image", f"png_ct{color_type}_{depth}bit.png", png(w, h, color_type, depth, rows, pal))

# ---- JPEG: baseline files whose every 8x8 block is flat (DC difference 0, then end-of-block), with one-code
# Huffman tables, so they can be written by hand: gray, and colour at 4:2:0 and 4:4:4
def jpeg(width, height, components, h_sampling):
    def segment(marker, body):
        return bytes([0xFF, marker]) + struct.pack(">H", len(body) + 2) + body
    out = b"\xff\xd8" + segment(0xDB, b"\x00" + bytes([1] * 64))  # one quantisation table of ones
    comps = [(1, h_sampling)] + [(2, 1), (3, 1)][: components - 1]
    out += segment(0xC0, struct.pack(">BHHB", 8, height, width, components) +
                   b"".join(bytes([cid, (hv << 4) | hv, 0]) for cid, hv in comps))
    one_code = bytes([1] + [0] * 15) + b"\x00"  # a single symbol, 0, with the one-bit code "0"
    out += segment(0xC4, b"\x00" + one_code) + segment(0xC4, b"\x10" + one_code)  # DC table 0, AC table 0
    out += segment(0xDA, bytes([components]) + b"".join(bytes([cid, 0x00]) for cid, _ in comps) + b"\x00\x3f\x00")
    mcu = 8 * h_sampling
    blocks = ((width + mcu - 1) // mcu) * ((height + mcu - 1) // mcu) * (h_sampling * h_sampling + components - 1)
    bits = "00" * blocks
    bits += "1" * (-len(bits) % 8)
    return out + bytes(int(bits[i:i + 8], 2) for i in range(0, len(bits), 8)) + b"\xff\xd9"


put("image", "jpeg_gray.jpg", jpeg(13, 9, 1, 1))
put("image", "jpeg_colour_420.jpg", jpeg(21, 17, 3, 2))
put("image", "jpeg_colour_444.jpg", jpeg(8, 8, 3, 1))

# ---- OBJ: colours, UV seams, negative indices, a quad, both companion materials
put("obj", "materials.obj",
    "# spot-like\nmtllib m.mtl\no thing\n"
    "v 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0 1 1 1\nv 0.5 0.5 1\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5\nvn 0 0 1\n"
    "usemtl textured\nf 1/1/1 2/2/1 3/3/1 4/4/1\nusemtl red\nf -5//1 -4//1 -1//1\ng side\ns off\n"
    "usemtl textured\nf 2/5 3/1 5/2\nf 3 4 5\nl 1 2\n")
put("obj", "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")

# ---- MTL: texture options, several materials, Tr and d
put("mtl", "options.mtl",
    "# materials\nnewmtl a\nKd 0.5 0.25 1\nd 0.5\nmap_Kd -s 1 1 1 -o 0 0 -clamp on -bm 0.2 my texture.png\n"
    "newmtl b\nKd 1 1 1\nTr 0.25\nKa 0 0 0\nillum 2\nnewmtl c d\nmap_Kd t.png\n")

# ---- PLY: ascii with texture and extra elements, binary little and big endian with colours
ply_header = ("ply\nformat {fmt} 1.0\ncomment TextureFile t.png\nelement vertex 4\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property uchar red\nproperty uchar green\nproperty uchar blue\n"
              "property float s\nproperty float t\n"
              "element face 2\nproperty list uchar int vertex_indices\nproperty uchar flags\n"
              "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n")
verts = [(0, 0, 0, 255, 0, 0, 0, 0), (1, 0, 0, 0, 255, 0, 1, 0), (1, 1, 0, 0, 0, 255, 1, 1), (0, 1, 0, 9, 9, 9, 0, 1)]
faces = [(3, 0, 1, 2), (3, 0, 2, 3)]
put("ply", "ascii.ply", ply_header.format(fmt="ascii") +
    "".join(" ".join(str(v) for v in p) + "\n" for p in verts) +
    "".join(" ".join(str(v) for v in f) + " 7\n" for f in faces) + "0 1\n")
for fmt, e in [("binary_little_endian", "<"), ("binary_big_endian", ">")]:
    body = b"".join(struct.pack(e + "fffBBBff", *p) for p in verts)
    body += b"".join(struct.pack(e + "Biii", *f) + b"\x07" for f in faces) + struct.pack(e + "ii", 0, 1)
    put("ply", f"{fmt}.ply", ply_header.format(fmt=fmt).encode() + body)
put("ply", "quad_ushort_colors.ply",
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\nproperty double z\n"
    "property ushort red\nproperty ushort green\nproperty ushort blue\n"
    "element face 1\nproperty list uchar uint vertex_index\nend_header\n"
    "0 0 0 65535 0 0\n1 0 0 0 65535 0\n1 1 0 0 0 65535\n0 1 0 1 2 3\n4 0 1 2 3\n")

# ---- glTF: a textured, vertex-coloured quad (indices, TRS node, child node) as .gltf and .glb
positions = struct.pack("<12f", 0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0)
colors = bytes([255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 9, 9, 9, 255])
uvs = struct.pack("<8f", 0, 0, 1, 0, 1, 1, 0, 1)
indices = struct.pack("<6H", 0, 1, 2, 0, 2, 3)
buffer = positions + colors + uvs + indices


def gltf_json(buffer_entry, image_entry):
    return {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "translation": [1, 0, 0], "rotation": [0, 0, 0.7071, 0.7071], "scale": [1, 2, -1],
                   "children": [1]},
                  {"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 3, 1]}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0, "COLOR_0": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0},
            {"attributes": {"POSITION": 0}, "mode": 5},
            {"attributes": {"POSITION": 0}, "mode": 6, "material": 1}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0.5, 0.5, 1], "baseColorTexture": {"index": 0}}},
                      {"name": "plain"}],
        "textures": [{"source": 0}],
        "images": [image_entry],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5121, "normalized": True, "count": 4, "type": "VEC4"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 16},
                        {"buffer": 0, "byteOffset": 64, "byteLength": 32}, {"buffer": 0, "byteOffset": 96, "byteLength": 12}],
        "buffers": [buffer_entry],
    }


uri = "data:application/octet-stream;base64," + base64.b64encode(buffer).decode()
put("gltf", "quad.gltf", json.dumps(gltf_json({"byteLength": len(buffer), "uri": uri}, {"uri": "t.png"}), indent=1))
tex = png(2, 2, 2, 8, [bytes([255, 0, 0, 0, 255, 0]), bytes([0, 0, 255, 255, 255, 255])])
bin_chunk = buffer + b"\0" * ((4 - len(buffer) % 4) % 4)
image_offset = len(bin_chunk)
bin_chunk += tex + b"\0" * ((4 - len(tex) % 4) % 4)
doc = gltf_json({"byteLength": len(bin_chunk)}, {"bufferView": 4, "mimeType": "image/png"})
doc["bufferViews"].append({"buffer": 0, "byteOffset": image_offset, "byteLength": len(tex)})
text = json.dumps(doc).encode()
text += b" " * ((4 - len(text) % 4) % 4)
glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(text) + 8 + len(bin_chunk))
glb += struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(bin_chunk), b"BIN\0") + bin_chunk
put("gltf", "quad.glb", glb)

# ---- config JSON: every getter's types, a scheduler config with trained_betas
put("config", "model.json", json.dumps({
    "_class_name": "UNet2DConditionModel", "sample_size": 32, "in_channels": 4.0, "norm_eps": 1e-5,
    "block_out_channels": [32, 64], "down_block_types": ["CrossAttnDownBlock2D", "DownBlock2D"],
    "attention_head_dim": [8, 8, 8, 8], "use_linear_projection": False, "only_cross_attention": None,
    "upcast_attention": True, "dropout": 0.0, "act_fn": "silu", "nested": {"height": 224, "width": 224}}))
put("config", "scheduler.json", json.dumps({
    "_class_name": "DDIMScheduler", "num_train_timesteps": 4, "beta_schedule": "linear",
    "trained_betas": [0.1, 0.2, 0.3, 0.4], "prediction_type": "v_prediction", "timestep_spacing": "trailing",
    "steps_offset": 1, "set_alpha_to_one": False, "clip_sample": False, "clip_sample_range": 1.5}))


# ---- pickles: protocol 2 state-dict shapes written by Python's own pickler with stand-in torch names
def fake_module(name, **attrs):
    m = types.ModuleType(name)
    for k, v in attrs.items():
        v.__module__ = name
        v.__qualname__ = k
        setattr(m, k, v)
    sys.modules[name] = m
    return m


class FloatStorage:
    pass


def _rebuild_tensor_v2(*args):
    pass


torch = fake_module("torch", FloatStorage=FloatStorage)
utils = fake_module("torch._utils", _rebuild_tensor_v2=_rebuild_tensor_v2)


class Tensor:
    def __init__(self, key, size):
        self.key, self.size = key, size

    def __reduce__(self):
        stride = tuple(int(x) for x in [1] * len(self.size))
        return (_rebuild_tensor_v2, (("storage", FloatStorage, self.key, "cpu", 4), 0, self.size, stride, False,
                                     collections.OrderedDict()))


class Pickler(pickle.Pickler):
    def persistent_id(self, obj):
        return obj if isinstance(obj, tuple) and obj and obj[0] == "storage" else None


def dumps(obj, protocol):
    import io
    out = io.BytesIO()
    Pickler(out, protocol=protocol).dump(obj)
    return out.getvalue()


state = collections.OrderedDict([("a.weight", Tensor("0", (2, 2))), ("a.bias", Tensor("1", (4,)))])
state._metadata = collections.OrderedDict([("", {"version": 1}), ("a", {"version": 1})])
put("pickle", "state_dict_p2.pkl", dumps(state, 2))
put("pickle", "state_dict_p4.pkl", dumps(state, 4))
put("pickle", "values_p2.pkl", dumps({"ints": [0, 1, -1, 300, 70000, 2**40, -2**63], "f": 1.5, "s": "x" * 300,
                                      "t": (1, (2, (3,))), "b": [True, False, None]}, 2))


# ---- zip directories of .pth checkpoints: torch.save's layout (an "archive/" folder, stored records),
# once plain and once with zip64 fields in every record
import io
import zipfile


def pth_zip(zip64):
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_STORED) as z:
        for name, data in [("archive/data.pkl", dumps(state, 2)), ("archive/data/0", bytes(range(64))),
                           ("archive/version", b"3\n")]:
            with z.open(zipfile.ZipInfo(name), "w", force_zip64=zip64) as f:
                f.write(data)
    return out.getvalue()


put("zip", "pth.zip", pth_zip(False))
put("zip", "pth_zip64.zip", pth_zip(True))


# ---- safetensors: every dtype the reader takes, an empty tensor, metadata, padding before the data
def safetensors(tensors, metadata=None, pad=0):
    header, data = {}, b""
    for name, (dtype, shape, raw) in tensors.items():
        header[name] = {"dtype": dtype, "shape": shape, "data_offsets": [len(data), len(data) + len(raw)]}
        data += raw
    if metadata:
        header["__metadata__"] = metadata
    text = json.dumps(header).encode() + b" " * pad
    return struct.pack("<Q", len(text)) + text + data


put("safetensors", "dtypes.safetensors", safetensors({
    "f32": ("F32", [2, 2], struct.pack("<4f", 1, -2, 0.5, 3)), "f16": ("F16", [3], struct.pack("<3e", 1, 2, -0.5)),
    "bf16": ("BF16", [2], b"\x80\x3f\x00\x40"), "f64": ("F64", [1], struct.pack("<d", 2.5)),
    "i64": ("I64", [2], struct.pack("<2q", -1, 2**40)), "i32": ("I32", [1, 1], struct.pack("<i", 7)),
    "u8": ("U8", [3], b"\x00\x7f\xff"), "bool": ("BOOL", [2], b"\x00\x01"), "empty": ("F32", [0, 3], b"")},
    metadata={"format": "pt"}, pad=5))
put("safetensors", "scalar.safetensors", safetensors({"s": ("F32", [], struct.pack("<f", 4))}))


# ---- ONNX: a model of two Conv nodes whose initializers use each way of storing data the reader knows
def varint(n):
    out = b""
    while True:
        b = n & 0x7F
        n >>= 7
        if n:
            out += bytes([b | 0x80])
        else:
            return out + bytes([b])


def field(number, value):
    if isinstance(value, int):
        return varint(number << 3) + varint(value)
    return varint(number << 3 | 2) + varint(len(value)) + value


def onnx_tensor(name, dims, data_type, payload):
    return b"".join(field(1, d) for d in dims) + field(2, data_type) + field(8, name.encode()) + payload


def onnx_node(op, name, inputs, outputs):
    return (b"".join(field(1, i.encode()) for i in inputs) + b"".join(field(2, o.encode()) for o in outputs) +
            field(3, name.encode()) + field(4, op.encode()))


initializers = [
    onnx_tensor("conv0.weight", [1, 1, 1, 1], 1, field(9, struct.pack("<f", 0.5))),           # raw_data
    onnx_tensor("conv0.bias", [1], 1, field(4, struct.pack("<f", 0.25))),                   # packed float_data
    onnx_tensor("onnx::Conv_7", [1, 1, 1, 1], 10, field(9, struct.pack("<e", 2))),          # fp16 raw_data
    onnx_tensor("onnx::Conv_8", [1], 11, field(10, struct.pack("<d", -1))),                 # double_data
    onnx_tensor("shape", [2], 7, field(7, varint(1) + varint(3))),                          # packed int64_data
    onnx_tensor("axes", [1], 6, field(5, varint(0))),                                       # int32_data
]
nodes = [onnx_node("Conv", "/conv0/Conv", ["x", "conv0.weight", "conv0.bias"], ["y"]),
         onnx_node("Relu", "/act/Relu", ["y"], ["z"]),
         onnx_node("Conv", "/conv1/Conv", ["z", "onnx::Conv_7", "onnx::Conv_8"], ["out"])]
graph = b"".join(field(1, n) for n in nodes) + field(2, b"tiny") + b"".join(field(5, t) for t in initializers)
put("onnx", "two_convs.onnx", field(1, 8) + field(2, b"pytorch") + field(7, graph))


# ---- state dicts for a torch.save archive: fuzz_state_dict stores the pickle next to records data/0 to
# data/3 of 16, 32, 64 and 0 bytes; a float view into a shared storage, a half storage, a parameter, a
# nested {"params_ema": ...} dict as basicsr saves it
class HalfStorage:
    pass


def _rebuild_parameter(*args):
    pass


torch.HalfStorage = HalfStorage
HalfStorage.__module__, HalfStorage.__qualname__ = "torch", "HalfStorage"
utils._rebuild_parameter = _rebuild_parameter
_rebuild_parameter.__module__, _rebuild_parameter.__qualname__ = "torch._utils", "_rebuild_parameter"


class View:
    def __init__(self, storage, key, numel, offset, size, stride):
        self.args = (("storage", storage, key, "cpu", numel), offset, size, stride)

    def __reduce__(self):
        return (_rebuild_tensor_v2, self.args + (False, collections.OrderedDict()))


class Parameter:
    def __init__(self, view):
        self.view = view

    def __reduce__(self):
        return (_rebuild_parameter, (self.view, True, collections.OrderedDict()))


archive_state = collections.OrderedDict([
    ("conv.weight", View(FloatStorage, "0", 4, 0, (2, 2), (2, 1))),
    ("conv.bias", View(FloatStorage, "0", 4, 2, (2,), (1,))),          # shares storage 0
    ("norm.weight", Parameter(View(HalfStorage, "1", 16, 0, (4, 4), (1, 4)))),  # transposed
    ("big", View(FloatStorage, "2", 16, 0, (16,), (1,))),
    ("empty", View(FloatStorage, "3", 0, 0, (0, 3), (3, 1)))])
put("state_dict", "views_p2.pkl", dumps(archive_state, 2))
put("state_dict", "nested_p4.pkl", dumps({"params_ema": archive_state}, 4))


# ---- whole .pth files as torch.save writes them (stored records under "<name>/", a byteorder record)
def pth_file(pkl, records):
    out = io.BytesIO()
    with zipfile.ZipFile(out, "w", compression=zipfile.ZIP_STORED) as z:
        for name, data in [("archive/data.pkl", pkl), ("archive/byteorder", b"little")] + records + \
                          [("archive/version", b"3\n")]:
            z.writestr(zipfile.ZipInfo(name), data)
    return out.getvalue()


put("pth", "views.pth", pth_file(dumps(archive_state, 2),
                                 [("archive/data/%d" % i, bytes(range(n))) for i, n in enumerate([16, 32, 64, 0])]))
