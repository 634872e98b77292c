#!/usr/bin/env python3
"""Packs a .gltf with one external .bin and external images into one .glb
(glTF 2.0 section 4.4): the images become buffer views after the .bin's
bytes. Used for the demo's built-in models (assets/).

    tools/pack_glb.py in.gltf out.glb
"""
import json
import os
import struct
import sys


def pad4(b, fill=b"\0"):
    return b + fill * (-len(b) % 4)


def main(src, dst):
    base = os.path.dirname(src)
    with open(src) as f:
        doc = json.load(f)
    if len(doc.get("buffers", [])) != 1:
        sys.exit(f"{src}: expected one buffer, found {len(doc.get('buffers', []))}")
    with open(os.path.join(base, doc["buffers"][0]["uri"]), "rb") as f:
        blob = f.read()
    mime = {".jpg": "image/jpeg", ".jpeg": "image/jpeg", ".png": "image/png"}
    for image in doc.get("images", []):
        uri = image.pop("uri")
        with open(os.path.join(base, uri), "rb") as f:
            data = f.read()
        blob = pad4(blob)
        doc.setdefault("bufferViews", []).append(
            {"buffer": 0, "byteOffset": len(blob), "byteLength": len(data)}
        )
        image["bufferView"] = len(doc["bufferViews"]) - 1
        image["mimeType"] = mime[os.path.splitext(uri)[1].lower()]
        blob += data
    blob = pad4(blob)
    doc["buffers"] = [{"byteLength": len(blob)}]
    text = pad4(json.dumps(doc, separators=(",", ":")).encode(), b" ")
    total = 12 + 8 + len(text) + 8 + len(blob)
    with open(dst, "wb") as f:
        f.write(struct.pack("<4sII", b"glTF", 2, total))
        f.write(struct.pack("<I4s", len(text), b"JSON") + text)
        f.write(struct.pack("<I4s", len(blob), b"BIN\0") + blob)


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
