"""MetaImage (.mha) reading for the figure scripts, without ITK's Python wrapping."""
import zlib

import numpy as np

_TYPES = {"MET_SHORT": np.int16, "MET_USHORT": np.uint16, "MET_FLOAT": np.float32, "MET_UCHAR": np.uint8}


def read_mha(path):
    """Returns (array indexed [z][y][x] or [y][x], spacing, origin) of a single-file MHA."""
    with open(path, "rb") as f:
        data = f.read()
    header = {}
    offset = 0
    while True:
        end = data.index(b"\n", offset)
        key, _, value = data[offset:end].decode().partition("=")
        header[key.strip()] = value.strip()
        offset = end + 1
        if key.strip() == "ElementDataFile":
            break
    raw = data[offset:]
    if header.get("CompressedData", "False") == "True":
        raw = zlib.decompress(raw)
    size = [int(v) for v in header["DimSize"].split()]
    array = np.frombuffer(raw, dtype=_TYPES[header["ElementType"]], count=int(np.prod(size))).reshape(size[::-1])
    spacing = [float(v) for v in header["ElementSpacing"].split()]
    origin = [float(v) for v in header.get("Offset", " ".join("0" * len(size))).split()]
    return array, spacing, origin
