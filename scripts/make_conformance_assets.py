#!/usr/bin/env python3
"""Writes the small hand-authored glTF files of assets/conformance/Authored/ (standard library only).

Each file isolates loader-side conformance cases no small Khronos sample model covers: material variants,
the material extensions without small samples (sheen, iridescence, dispersion, diffuse transmission) plus
out-of-range values, a texture whose only image is KTX2, and pieces raykin ignores (an unknown extension,
KHR_lights_punctual, an occlusion texture, a points primitive). Run from the repository root:
    python3 scripts/make_conformance_assets.py
"""

import base64
import json
import os
import struct

OUT = os.path.join("assets", "conformance", "Authored")


def data_uri(data: bytes, mime: str = "application/octet-stream") -> str:
    return f"data:{mime};base64," + base64.b64encode(data).decode()


def quad_buffer(offset_x: float = 0.0):
    """A unit quad in the XY plane facing +Z: positions, normals, uvs (float) and u16 indices."""
    positions = [(offset_x - 0.5, -0.5, 0.0), (offset_x + 0.5, -0.5, 0.0), (offset_x + 0.5, 0.5, 0.0), (offset_x - 0.5, 0.5, 0.0)]
    normals = [(0.0, 0.0, 1.0)] * 4
    uvs = [(0.0, 1.0), (1.0, 1.0), (1.0, 0.0), (0.0, 0.0)]
    indices = [0, 1, 2, 0, 2, 3]
    data = b"".join(struct.pack("<3f", *p) for p in positions)
    data += b"".join(struct.pack("<3f", *n) for n in normals)
    data += b"".join(struct.pack("<2f", *t) for t in uvs)
    data += struct.pack("<6H", *indices) + b"\0\0"
    return data, positions


def quad_document(materials, extensions_used, primitive_extra=None, extra_meshes=()):
    data, positions = quad_buffer()
    xs = [p[0] for p in positions]
    ys = [p[1] for p in positions]
    primitive = {
        "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
        "indices": 3,
        "material": 0,
    }
    primitive.update(primitive_extra or {})
    doc = {
        "asset": {"version": "2.0", "generator": "raykin scripts/make_conformance_assets.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"name": "quad", "primitives": [primitive]}],
        "materials": materials,
        "buffers": [{"byteLength": len(data), "uri": data_uri(data)}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48, "target": 34962},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48, "target": 34962},
            {"buffer": 0, "byteOffset": 96, "byteLength": 32, "target": 34962},
            {"buffer": 0, "byteOffset": 128, "byteLength": 12, "target": 34963},
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [min(xs), min(ys), 0.0], "max": [max(xs), max(ys), 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"},
        ],
    }
    for mesh in extra_meshes:
        doc["meshes"].append(mesh)
        doc["nodes"].append({"mesh": len(doc["meshes"]) - 1})
        doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)
    if extensions_used:
        doc["extensionsUsed"] = extensions_used
    return doc


def png_1x1(rgba) -> bytes:
    import zlib

    def chunk(kind, payload):
        return struct.pack(">I", len(payload)) + kind + payload + struct.pack(">I", zlib.crc32(kind + payload))

    raw = b"\0" + bytes(rgba)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 1, 1, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def write(name, doc):
    with open(os.path.join(OUT, name), "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")


def main():
    os.makedirs(OUT, exist_ok=True)

    # KHR_materials_variants: one primitive, three materials, two variants (`red` maps to material 1,
    # `blue` to material 2; without a selection the primitive keeps material 0).
    mat = lambda name, rgb: {"name": name, "pbrMetallicRoughness": {"baseColorFactor": rgb + [1.0], "metallicFactor": 0.0}}
    write("MaterialVariants.gltf", dict(
        quad_document(
            [mat("grey", [0.5, 0.5, 0.5]), mat("red", [0.8, 0.1, 0.1]), mat("blue", [0.1, 0.1, 0.8])],
            ["KHR_materials_variants"],
            {"extensions": {"KHR_materials_variants": {"mappings": [
                {"material": 1, "variants": [0]}, {"material": 2, "variants": [1]}]}}},
        ),
        extensions={"KHR_materials_variants": {"variants": [{"name": "red"}, {"name": "blue"}]}},
    ))

    # Material extensions with in-range values (material 0) and values outside their schema range
    # (material 1: each must be clamped or replaced with a warning, never passed on).
    good = {
        "name": "layered",
        "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1.0], "metallicFactor": 0.0},
        "extensions": {
            "KHR_materials_ior": {"ior": 1.7},
            "KHR_materials_transmission": {"transmissionFactor": 0.8},
            "KHR_materials_volume": {"thicknessFactor": 0.25, "attenuationDistance": 2.0,
                                     "attenuationColor": [0.9, 0.5, 0.2]},
            "KHR_materials_specular": {"specularFactor": 0.7, "specularColorFactor": [1.0, 0.9, 0.8]},
            "KHR_materials_clearcoat": {"clearcoatFactor": 0.6, "clearcoatRoughnessFactor": 0.2},
            "KHR_materials_sheen": {"sheenColorFactor": [0.3, 0.2, 0.1], "sheenRoughnessFactor": 0.5},
            "KHR_materials_iridescence": {"iridescenceFactor": 1.0, "iridescenceIor": 1.8,
                                          "iridescenceThicknessMinimum": 200, "iridescenceThicknessMaximum": 600},
            "KHR_materials_anisotropy": {"anisotropyStrength": 0.5, "anisotropyRotation": 0.75},
            "KHR_materials_dispersion": {"dispersion": 0.33},
            "KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 0.4,
                                                   "diffuseTransmissionColorFactor": [0.2, 0.9, 0.3]},
            "KHR_materials_emissive_strength": {"emissiveStrength": 4.0},
        },
        "emissiveFactor": [0.1, 0.1, 0.1],
    }
    bad = {
        "name": "out of range",
        "extensions": {
            "KHR_materials_ior": {"ior": 0.5},
            "KHR_materials_transmission": {"transmissionFactor": 3.0},
            "KHR_materials_volume": {"thicknessFactor": 1e39, "attenuationDistance": 0.0,
                                     "attenuationColor": [2.0, -1.0, 0.5]},
            "KHR_materials_clearcoat": {"clearcoatFactor": -0.5, "clearcoatRoughnessFactor": "rough"},
            "KHR_materials_sheen": {"sheenColorFactor": [1.5, 0.5], "sheenRoughnessFactor": 2.0},
            "KHR_materials_iridescence": {"iridescenceIor": -1.0},
            "KHR_materials_anisotropy": {"anisotropyStrength": 7.0},
            "KHR_materials_dispersion": {"dispersion": -2.0},
            "KHR_materials_diffuse_transmission": {"diffuseTransmissionFactor": 1.5},
        },
    }
    zero_ior = {"name": "ior zero", "extensions": {"KHR_materials_ior": {"ior": 0.0}}}
    used = sorted({k for m in (good, bad) for k in m["extensions"]})
    second = {"name": "quad 1", "primitives": [{"attributes": {"POSITION": 0}, "indices": 3, "material": 1}]}
    third = {"name": "quad 2", "primitives": [{"attributes": {"POSITION": 0}, "indices": 3, "material": 2}]}
    write("MaterialExtensions.gltf", quad_document([good, bad, zero_ior], used, extra_meshes=[second, third]))

    # KHR_texture_basisu as the only image of a texture: KTX2 is not decoded, so the material falls back to
    # its factor with a warning. The image is a KTX2 identifier and an empty header (enough to be known).
    ktx2 = bytes([0xAB, 0x4B, 0x54, 0x58, 0x20, 0x32, 0x30, 0xBB, 0x0D, 0x0A, 0x1A, 0x0A]) + bytes(68)
    doc = quad_document(
        [{"name": "ktx2 only", "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.6, 0.2, 1.0],
                                                       "baseColorTexture": {"index": 0}}}],
        ["KHR_texture_basisu"],
    )
    doc["extensionsRequired"] = ["KHR_texture_basisu"]
    doc["images"] = [{"uri": data_uri(ktx2, "image/ktx2"), "mimeType": "image/ktx2"}]
    doc["textures"] = [{"extensions": {"KHR_texture_basisu": {"source": 0}}}]
    write("Ktx2OnlyTexture.gltf", doc)

    # Pieces raykin ignores, each to be named once: an unknown extension, KHR_lights_punctual, an occlusion
    # texture, a POINTS primitive, an image without a URI (in a bufferView) that cannot be decoded.
    doc = quad_document(
        [{"name": "occluded", "occlusionTexture": {"index": 0},
          "pbrMetallicRoughness": {"baseColorTexture": {"index": 1}}}],
        ["EXT_raykin_unknown", "KHR_lights_punctual"],
        extra_meshes=[{"name": "points", "primitives": [{"attributes": {"POSITION": 0}, "mode": 0}]}],
    )
    png = png_1x1([200, 100, 50, 255])
    garbage = b"not an image at all"
    buffer = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
    png_offset = len(buffer)
    buffer += png + bytes((4 - len(png) % 4) % 4)
    garbage_offset = len(buffer)
    buffer += garbage
    doc["buffers"][0] = {"byteLength": len(buffer), "uri": data_uri(buffer)}
    doc["bufferViews"] += [
        {"buffer": 0, "byteOffset": png_offset, "byteLength": len(png)},
        {"buffer": 0, "byteOffset": garbage_offset, "byteLength": len(garbage)},
    ]
    doc["images"] = [{"bufferView": 4, "mimeType": "image/png"}, {"bufferView": 5, "mimeType": "image/png"}]
    doc["textures"] = [{"source": 0}, {"source": 1}]
    doc["extensions"] = {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10.0}]}}
    write("IgnoredPieces.gltf", doc)


if __name__ == "__main__":
    main()
