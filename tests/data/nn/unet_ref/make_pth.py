#!/usr/bin/python3
# Writes the two torch-format checkpoints the image2normal loading tests read (tests/nn/test_unique3d_normal.cpp),
# from this case's safetensors files, as Unique3D's unet_state_dict.pth would hold them (torch.save of a
# state dict, an OrderedDict):
#   weights.pth           the main UNet only (the official file without "ref_unet.")
#   weights_ref_unet.pth  the main UNet plus the reference UNet (../unet_base) under "ref_unet."
# Needs Debian's python3-torch. Run from this folder: /usr/bin/python3 make_pth.py
import collections
import json
import struct

import numpy as np
import torch


def read_safetensors(path):
    with open(path, "rb") as f:
        data = f.read()
    (size,) = struct.unpack("<Q", data[:8])
    header = json.loads(data[8:8 + size])
    body = data[8 + size:]
    tensors = collections.OrderedDict()
    for name, info in header.items():
        if name == "__metadata__":
            continue
        assert info["dtype"] == "F32", name
        begin, end = info["data_offsets"]
        array = np.frombuffer(body[begin:end], dtype="<f4").reshape(info["shape"])
        tensors[name] = torch.from_numpy(array.copy())
    return tensors


main = read_safetensors("weights.safetensors")
torch.save(main, "weights.pth")
full = collections.OrderedDict(main)
for name, tensor in read_safetensors("../unet_base/weights.safetensors").items():
    full["ref_unet." + name] = tensor
torch.save(full, "weights_ref_unet.pth")
