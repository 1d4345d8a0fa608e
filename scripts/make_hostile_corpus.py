#!/usr/bin/env python3
"""Writes the hostile-input corpus (issue #14) into a directory: broken OBJ, glTF, GLB, STL, PLY
and OFF files, absurd counts and sizes, odd encodings, special files (a FIFO, a directory, symbolic
links), and a manifest.json saying, per file, what each command must do with it.

    python3 scripts/make_hostile_corpus.py OUT_DIR

Generated at test time (CTest fixture `hostile.generate`), never committed. The runner is
tests/hostile/run_hostile.py; docs/hardening.md explains the checks.

Manifest entry: {"name", "path" (relative to OUT_DIR, or absolute for /dev/zero),
"expect": {command: {"exit": N, "message": REGEX}}}, where command is info, convert, refine,
limit or python; "args" per command add options; a missing command uses "default".
Messages are Python regular expressions searched in stderr (for python: the exception's
class name and message).
"""
import base64
import json
import math
import os
import random
import struct
import sys

CUBE_V = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
          (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]
CUBE_F = [(1, 4, 3, 2), (5, 6, 7, 8), (1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (4, 1, 5, 8)]


def obj_text(vertices=CUBE_V, faces=CUBE_F, extra="", newline="\n", vfmt="%r"):
    lines = ["v " + " ".join(vfmt % c for c in v) for v in vertices]
    lines += ["f " + " ".join(str(i) for i in f) for f in faces]
    text = newline.join(lines) + newline
    return text + extra


CUBE = obj_text()


def grid(n):
    """An n x n quad grid (open), OBJ text."""
    out = []
    for j in range(n + 1):
        for i in range(n + 1):
            out.append("v %d %d 0\n" % (i, j))
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            out.append("f %d %d %d %d\n" % (a, a + 1, a + n + 2, a + n + 1))
    return "".join(out)


def cone(n):
    """A fan of n triangles around one apex with a closing base n-gon... split in quads is
    not needed: the apex has valence n (closed surface: fan + base face would be an n-gon, so
    the base stays open)."""
    out = ["v 0 0 1\n"]
    for k in range(n):
        a = 2 * math.pi * k / n
        out.append("v %.9f %.9f 0\n" % (math.cos(a), math.sin(a)))
    for k in range(n):
        out.append("f 1 %d %d\n" % (2 + k, 2 + (k + 1) % n))
    return "".join(out)


# --- glTF ---------------------------------------------------------------------------------------

CUBE_TRI_POS = [c for v in CUBE_V for c in v]
CUBE_TRI_IDX = []
for f in CUBE_F:
    a, b, c, d = (i - 1 for i in f)
    CUBE_TRI_IDX += [a, b, c, a, c, d]


def gltf_model(positions=None, indices=None, position_count=None, index_count=None, nodes=None, scenes=None,
               mode=None, pos_type="VEC3", pos_component=5126, idx_component=5125, extra_buffer_views=None,
               byte_stride=None, sparse=False, mesh_index=0, buffer_uri=None, buffer_length=None,
               drop_position=False, images=None):
    positions = CUBE_TRI_POS if positions is None else positions
    indices = CUBE_TRI_IDX if indices is None else indices
    pos_bytes = struct.pack("<%df" % len(positions), *positions)
    idx_fmt = {5121: "B", 5123: "H", 5125: "I", 5126: "f"}[idx_component]
    idx_bytes = struct.pack("<%d%s" % (len(indices), idx_fmt), *indices)
    while len(pos_bytes) % 4:
        pos_bytes += b"\0"
    data = pos_bytes + idx_bytes
    while len(data) % 4:
        data += b"\0"
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos_bytes)},
             {"buffer": 0, "byteOffset": len(pos_bytes), "byteLength": len(idx_bytes)}]
    if byte_stride is not None:
        views[0]["byteStride"] = byte_stride
    if extra_buffer_views:
        views += extra_buffer_views
    pos_acc = {"bufferView": 0, "componentType": pos_component, "type": pos_type,
               "count": position_count if position_count is not None else len(positions) // 3}
    if pos_type == "VEC3" and pos_component == 5126 and all(math.isfinite(p) for p in positions) and positions:
        pos_acc["min"] = [min(positions[k::3]) for k in range(3)]
        pos_acc["max"] = [max(positions[k::3]) for k in range(3)]
    if sparse:
        pos_acc["sparse"] = {"count": 1, "indices": {"bufferView": 1, "componentType": 5125},
                             "values": {"bufferView": 0}}
    idx_acc = {"bufferView": 1, "componentType": idx_component, "type": "SCALAR",
               "count": index_count if index_count is not None else len(indices)}
    prim = {"attributes": {} if drop_position else {"POSITION": 0}, "indices": 1}
    if mode is not None:
        prim["mode"] = mode
    model = {
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": buffer_length if buffer_length is not None else len(data)}],
        "bufferViews": views,
        "accessors": [pos_acc, idx_acc],
        "meshes": [{"primitives": [prim]}],
        "nodes": nodes if nodes is not None else [{"mesh": mesh_index}],
        "scenes": scenes if scenes is not None else [{"nodes": [0]}],
        "scene": 0,
    }
    if images:
        model["images"] = images
    if buffer_uri is not None:
        model["buffers"][0]["uri"] = buffer_uri
    return model, data


def gltf_text(model, data):
    if "uri" not in model["buffers"][0]:
        model["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    return json.dumps(model).encode()


def glb_bytes(model, data, truncate=None, magic=b"glTF"):
    model = dict(model)
    body = json.dumps(model).encode()
    while len(body) % 4:
        body += b" "
    out = struct.pack("<I", len(body)) + b"JSON" + body + struct.pack("<I", len(data)) + b"BIN\0" + data
    out = magic + struct.pack("<II", 2, 12 + len(out)) + out
    return out[:truncate] if truncate else out


# --- STL, PLY, OFF (io/mesh_reader.h); faces as 0-based index tuples ------------------------

CUBE_TRIANGLES = [t for q in CUBE_F for t in ((q[0] - 1, q[1] - 1, q[2] - 1), (q[0] - 1, q[2] - 1, q[3] - 1))]


def stl_binary(triangles=CUBE_TRIANGLES, vertices=CUBE_V, header=b"binary", count=None):
    out = header.ljust(80, b" ")[:80] + struct.pack("<I", len(triangles) if count is None else count)
    for t in triangles:
        out += struct.pack("<3f", 0, 0, 0) + b"".join(struct.pack("<3f", *vertices[v]) for v in t) + b"\0\0"
    return out


def stl_ascii(triangles=CUBE_TRIANGLES, vertices=CUBE_V):
    facets = "".join("facet normal 0 0 0\nouter loop\n" + "".join("vertex %r %r %r\n" % vertices[v] for v in t) +
                     "endloop\nendfacet\n" for t in triangles)
    return "solid cube\n" + facets + "endsolid cube\n"


def off_text(faces=[tuple(v - 1 for v in f) for f in CUBE_F], vertices=CUBE_V, keyword="OFF", counts=None):
    nv, nf = counts or (len(vertices), len(faces))
    return ("%s\n%d %d 0\n" % (keyword, nv, nf) + "".join("%r %r %r\n" % v for v in vertices) +
            "".join("%d %s\n" % (len(f), " ".join(map(str, f))) for f in faces))


def ply_binary_big(faces=[tuple(v - 1 for v in f) for f in CUBE_F], vertices=CUBE_V, count_type="uchar"):
    header = ("ply\nformat binary_big_endian 1.0\nelement vertex %d\nproperty double x\nproperty double y\n"
              "property double z\nelement face %d\nproperty list %s int vertex_indices\nend_header\n"
              % (len(vertices), len(faces), count_type)).encode()
    count = {"uchar": "B", "uint": "I"}[count_type]
    return header + b"".join(struct.pack(">3d", *v) for v in vertices) + b"".join(
        struct.pack(">" + count + "%di" % len(f), len(f), *f) for f in faces)


# --- the corpus -----------------------------------------------------------------------------

class Corpus:
    def __init__(self, root):
        self.root = root
        self.cases = []
        os.makedirs(root, exist_ok=True)

    def add(self, name, content=None, expect=None, args=None, path=None, kind="input"):
        if content is not None:
            with open(os.path.join(self.root, name), "wb") as f:
                f.write(content if isinstance(content, bytes) else content.encode("utf-8", "surrogateescape"))
        self.cases.append({"name": name, "path": path or name, "expect": expect or {}, "args": args or {},
                           "kind": kind})

    def invalid(self, name, content, message, **kw):
        """Every command refuses it as invalid input (exit 2) with `message` in stderr."""
        self.add(name, content, {"default": {"exit": 2, "message": message}}, **kw)

    def write_manifest(self):
        with open(os.path.join(self.root, "manifest.json"), "w") as f:
            json.dump({"cases": self.cases}, f, indent=1)


OK = {"exit": 0, "message": ""}


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    c = Corpus(sys.argv[1])
    rng = random.Random(14)

    # --- encodings ---
    c.add("bom_cube.obj", b"\xef\xbb\xbf" + CUBE.encode(),
          {"default": OK, "info": {"exit": 0, "message": "", "stdout": r"vertices +8 .*\n +faces +6"}})
    c.invalid("utf16le_bom.obj", b"\xff\xfe" + CUBE.encode("utf-16-le"), r":1: error: .*UTF-16")
    c.invalid("utf16be_bom.obj", b"\xfe\xff" + CUBE.encode("utf-16-be"), r":1: error: .*UTF-16")
    c.invalid("utf16le_nobom.obj", CUBE.encode("utf-16-le"), r":1: error: .*UTF-16")
    c.invalid("utf32le_bom.obj", b"\xff\xfe\0\0" + CUBE.encode("utf-32-le"), r":1: error: .*UTF-32")
    c.add("crlf_cube.obj", obj_text(newline="\r\n"), {"default": OK})
    c.add("cr_cube.obj", obj_text(newline="\r"), {"default": OK})
    c.add("no_final_newline.obj", CUBE.rstrip("\n"), {"default": OK})
    c.add("latin1_comment.obj", b"# caf\xe9 \xff\xfe\n" + CUBE.encode(), {"default": OK})
    c.add("bom_cube.gltf", b"\xef\xbb\xbf" + gltf_text(*gltf_model()), {"default": OK})
    c.invalid("utf16_cube.gltf", gltf_text(*gltf_model()).decode().encode("utf-16"), r"error: .*(UTF-16|glTF)")

    # --- empty and nearly empty ---
    c.invalid("empty.obj", b"", r"empty\.obj: error: .*no mesh")
    c.invalid("comments_only.obj", "# nothing\n# here\n", r"no mesh")
    c.invalid("vertices_only.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n", r"no mesh")
    c.invalid("faces_only.obj", "f 1 2 3\n", r"faces_only\.obj: error: the file defines no mesh \(0 vertices, 1 faces\)")
    c.invalid("whitespace.obj", " \t\n" * 1000, r"no mesh")
    c.invalid("binary_garbage.obj", bytes(rng.getrandbits(8) for _ in range(65536)), r"error: ")
    c.invalid("nul_bytes.obj", b"v\0 0 0 0\n" * 3 + b"f 1 2 3\n", r"error: ")

    # --- coordinates ---
    for tag, value, msg in [("nan", "nan", "non-finite"), ("inf", "inf", "non-finite"), ("minus_inf", "-inf", "non-finite"),
                            ("1e400", "1e400", "non-finite"), ("1e200", "1e200", "coordinate limit"),
                            ("1e308", "1.7e308", "coordinate limit"), ("1e16", "1e16", "coordinate limit"),
                            ("minus_1e16", "-1e16", "coordinate limit"), ("1e150", "1e150", "coordinate limit")]:
        text = CUBE.replace("v 1 1 1", "v %s 1 1" % value, 1)
        c.invalid("coord_%s.obj" % tag, text, r":7: error: vertex 7 .*" + msg)
    c.add("coord_1e14_scale.obj", obj_text([tuple(1e14 * x for x in v) for v in CUBE_V]), {"default": OK})
    c.add("coord_1e-6_scale.obj", obj_text([tuple(1e-6 * x for x in v) for v in CUBE_V]), {"default": OK})
    c.invalid("coord_hex.obj", CUBE.replace("v 1 1 1", "v 0x1p3 1 1", 1), r":7: error: .*not a number")
    c.invalid("coord_comma.obj", CUBE.replace("v 1 1 1", "v 1,5 1 1", 1), r":7: error: .*not a number")
    c.invalid("coord_two.obj", CUBE.replace("v 1 1 1", "v 1 1", 1), r":7: error: .*3 coordinates")
    c.invalid("coord_huge_token.obj", CUBE.replace("v 1 1 1", "v 1" + "1" * 400000 + " 1 1", 1),
              r":7: error: .*non-finite")
    c.add("all_points_equal.obj", obj_text([(1, 1, 1)] * 8),
          {"default": OK, "convert": {"exit": 2, "message": r"all_points_equal\.obj: error: .*vertices coincide"},
           "python": {"exit": 2, "message": r"CageError: .*vertices coincide"}})
    c.add("far_and_tiny.obj", obj_text([(1e14 + 1e-4 * x, y * 1e-4, z * 1e-4) for x, y, z in CUBE_V]),
          {"default": OK, "convert": {"exit": 2, "message": r"below what double precision resolves"},
           "python": {"exit": 2, "message": r"CageError: .*double precision"}})

    # --- faces ---
    c.invalid("face_two.obj", CUBE + "f 1 2\n", r":15: error: .*at least 3")
    c.invalid("face_index_zero.obj", CUBE + "f 0 1 2\n", r":15: error: .*index 0")
    c.invalid("face_index_99.obj", CUBE + "f 1 2 99\n", r":15: error: .*vertex 99")
    c.invalid("face_relative_too_far.obj", CUBE + "f -1 -2 -100\n", r":15: error: .*relative")
    c.invalid("face_index_int_overflow.obj", CUBE + "f 1 2 99999999999\n", r":15: error: .*not a vertex index")
    c.invalid("face_index_words.obj", CUBE + "f a b c\n", r":15: error: .*not a vertex index")
    c.invalid("face_four_slashes.obj", CUBE + "f 1/1/1/1 2 3\n", r":15: error: .*more than 3")
    c.invalid("face_repeated.obj", CUBE.replace("f 1 4 3 2", "f 1 4 3 1"), r":9: error: .*twice")
    c.invalid("face_duplicate.obj", CUBE + "f 1 4 3 2\n", r":15: error: ")
    c.invalid("nonmanifold_edge.obj", obj_text(CUBE_V + [(0, -2, 0)], CUBE_F + [(1, 2, 9)]),
              r":16: error: non-manifold edge 2-1: shared by 3 faces \(lines 10, 12, 16\)")
    c.invalid("flipped_face.obj", CUBE.replace("f 5 6 7 8", "f 8 7 6 5"), r":13: error: face is oriented inconsistently with its neighbour on line 10")
    c.invalid("bowtie_vertex.obj",
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv -1 0 0\nv 0 -1 0\nf 1 2 3\nf 1 4 5\n", r":1: error: .*non-manifold")
    c.invalid("face_1025.obj", cone(1025).replace("f 1 2 3\n", "") + "f " + " ".join(str(i) for i in range(2, 1027)) + "\n",
              r"error: .*(1025 vertices; at most 1024|valence 1025)")
    c.invalid("face_100000.obj",
              "".join("v %d %d 0\n" % (math.cos(k) * 1000, math.sin(k) * 1000) for k in range(1))
              + "".join("v %.6f %.6f 0\n" % (math.cos(2 * math.pi * k / 100000), math.sin(2 * math.pi * k / 100000))
                        for k in range(100000)) + "f " + " ".join(str(i) for i in range(2, 100002)) + "\n",
              r":100002: error: face has 100000 vertices; at most 1024")
    c.invalid("valence_1025.obj", cone(1025), r":1: error: vertex 1 has valence 1025; at most 1024")
    c.invalid("valence_2000.obj", cone(2000), r":1: error: vertex 1 has valence 2000")
    c.add("valence_24.obj", cone(24), {"default": OK})

    # --- tags ---
    c.invalid("tag_counts_missing.obj", CUBE + "t crease\n", r":15: error: .*crease")
    c.invalid("tag_counts_bad.obj", CUBE + "t crease 2/1 0 1 1\n", r":15: error: .*nint/nfloat/nstring")
    c.invalid("tag_counts_huge.obj", CUBE + "t crease 999999999/1/0 0 1 2\n", r":15: error: .*announces")
    c.invalid("tag_counts_overflow.obj", CUBE + "t crease 2147483648/1/0 0 1 2\n", r":15: error: .*nint/nfloat/nstring")
    c.invalid("tag_counts_negative.obj", CUBE + "t crease -2/1/0 0 1 2\n", r":15: error: ")
    c.invalid("crease_not_edge.obj", CUBE + "t crease 2/1/0 0 6 2\n", r":15: error: .*not an edge")
    c.invalid("crease_negative.obj", CUBE + "t crease 2/1/0 0 1 -1\n", r":15: error: .*sharpness")
    c.invalid("crease_nan.obj", CUBE + "t crease 2/1/0 0 1 nan\n", r":15: error: .*sharpness")
    c.invalid("corner_out_of_range.obj", CUBE + "t corner 1/1/0 99 2\n", r":15: error: .*corner names vertex 99")
    c.invalid("hole_out_of_range.obj", CUBE + "t hole 1/0/0 99\n", r":15: error: .*hole names face 99")
    c.invalid("interpolateboundary_7.obj", CUBE + "t interpolateboundary 1/0/0 7\n", r":15: error: .*is not 0")
    c.invalid("creasemethod_bogus.obj", CUBE + "t creasemethod 0/0/1 bogus\n", r":15: error: .*normal")
    c.invalid("smoothtriangles_bogus.obj", CUBE + "t smoothtriangles 0/0/1 x\n", r":15: error: .*catmark")
    c.add("all_holes.obj", CUBE + "t hole 6/0/0 0 1 2 3 4 5\n",
          {"default": OK, "convert": {"exit": 2, "message": r"all_holes\.obj: error: every face .* hole"},
           "python": {"exit": 2, "message": r"CageError: every face .* hole"},
           "limit": {"exit": 2, "message": r"hole"}})
    c.add("unknown_tag.obj", CUBE + "t vertexedit 0/0/0\n", {"default": OK})

    # --- names and tokens echoed in messages ---
    c.add("long_statement.obj", CUBE + "x" * 1000000 + " 1 2 3\n",
          {"default": OK, "info": {"exit": 0, "message": "", "max_output": 20000}})
    c.add("control_statement.obj", CUBE + "\x1b[31mred\x1b[0m 1\n",
          {"default": OK, "info": {"exit": 0, "message": "", "stdout": r"\\x1b\[31mred"}})
    c.invalid("nul_in_token.obj", CUBE.replace("v 1 1 1", "v 1\x002 1 1", 1), r":7: error: .*\\x00")
    c.invalid("long_face_token.obj", CUBE + "f 1 2 " + "z" * 500000 + "\n", r":15: error: .*\.\.\.\(500000 bytes\)")

    # --- sizes: resource guards ---
    c.add("grid_520.obj", grid(520),
          # 270 400 regular quads, packed into one face: 936 MiB estimated (#32: about 3.2 KB a quad
          # measured, docs/hardening.md), refused under a 512 MiB limit.
          {"default": OK, "convert": {"exit": 1, "message": r"would need about 936 MiB of memory \(limit 512 MiB\).*--max-memory"},
           "python": {"exit": 1, "message": r"SettingsError: .*memory"},
           "refine": {"exit": 1, "message": r"about 6\.92e\+07 faces .*--max-faces"}},
          args={"refine": ["-l", "4"], "convert": ["--max-memory", "512M"], "python": {"max_memory": "512M"}})
    c.add("grid_100.obj", grid(100), {}, kind="signal")
    # The signal test's cage: it stops at a known stage (SUBD2NURBS_TEST_STOP), so a small one.
    c.add("grid_10.obj", grid(10), {}, kind="signal")
    # A semi-sharp crease makes the patch builder refine until it has decayed (5 levels here),
    # but only the pieces next to it: the 10k-quad grid converts (it once refined the whole
    # cage to 10k x 4^5 faces and timed out).
    c.add("grid_100_crease5.obj", grid(100) + "t crease 2/1/0 102 103 5\n",
          {"default": OK},
          args={"refine": ["-l", "1"]})  # for the SIGTERM / SIGINT runs only
    c.add("cube_refine_11.obj", CUBE,
          {"default": OK, "refine": {"exit": 1, "message": r"refining 6 faces to level 11 would make about 2\.52e\+07 faces"}},
          args={"refine": ["-l", "11"]})
    # 12 extra levels cost the cube a few knots per corner (it once meant 6 x 4^14 faces): the
    # estimate, 1 062 pieces (960 built), passes the default and is refused below it.
    c.add("cube_level_12.obj", CUBE,
          {"default": OK, "convert": {"exit": 1, "message": r"level 12 would make about 1\.06e\+03 .*--max-faces"},
           "python": {"exit": 1, "message": r"SettingsError: .*level 12"}},
          args={"convert": ["--level", "12", "--max-faces", "1000"], "python": {"level": 12, "max_faces": 1000}})
    c.add("cube_max_memory.obj", CUBE,
          {"default": OK, "convert": {"exit": 1, "message": r"memory \(limit 1 KiB\).*--max-memory"},
           "refine": {"exit": 1, "message": r"memory \(limit 1 KiB\)"},
           "python": {"exit": 1, "message": r"SettingsError: .*memory"}},
          args={"convert": ["--max-memory", "1K"], "refine": ["-l", "1", "--max-memory", "1K"],
                "python": {"max_memory": "1K"}})
    c.add("cube_max_memory_bogus.obj", CUBE,
          {"default": OK, "convert": {"exit": 1, "message": r"--max-memory '12Q' is not a size"},
           "refine": {"exit": 1, "message": r"--max-memory '12Q'"},
           "python": {"exit": 1, "message": r"SettingsError: max_memory '12Q'"}},
          args={"convert": ["--max-memory", "12Q"], "refine": ["-l", "1", "--max-memory", "12Q"],
                "python": {"max_memory": "12Q"}})
    c.add("cube_max_faces_1.obj", CUBE,
          {"default": OK, "convert": {"exit": 1, "message": r"\(limit 1\)"},
           "python": {"exit": 1, "message": r"SettingsError: .*\(limit 1\)"}},
          args={"convert": ["--max-faces", "1"], "python": {"max_faces": 1}})
    c.add("grid_520_override.obj", None,
          {"default": OK, "refine": OK, "convert": {"exit": 0, "message": ""}},
          args={"convert": ["--max-faces", "5e6", "--quiet"], "refine": ["-l", "1"], "python": {"max_faces": 5e6},
                "skip": ["python", "convert"]}, path="grid_520.obj")

    # --- glTF / GLB ---
    m, d = gltf_model()
    c.add("cube.gltf", gltf_text(m, d), {"default": OK})
    c.add("cube.glb", glb_bytes(*gltf_model()), {"default": OK})
    m, d = gltf_model(position_count=400000000)
    c.invalid("count_4e8.glb", glb_bytes(m, d), r"error: accessor 0 \(POSITION of mesh 0 primitive 0\): count 400000000 needs more bytes")
    m, d = gltf_model(index_count=400000000)
    c.invalid("index_count_4e8.gltf", gltf_text(m, d), r"error: accessor 1 \(indices of mesh 0 primitive 0\): count 400000000")
    m, d = gltf_model(position_count=2 ** 62)
    c.invalid("count_2e62.glb", glb_bytes(m, d), r"error: (accessor 0|not a readable glTF)")
    nodes = [{"children": [i + 1, i + 1]} for i in range(27)] + [{"mesh": 0}]
    m, d = gltf_model(nodes=nodes)
    c.invalid("instance_bomb_2e27.glb", glb_bytes(m, d), r"error: node \d+: the scene expands to more than 100000 node instances")
    nodes = [{"children": [1] * 400}, {"children": [2] * 400}, {"mesh": 0}]
    m, d = gltf_model(nodes=nodes)
    c.invalid("instance_wide.gltf", gltf_text(m, d), r"error: node \d+: the scene expands")
    pos = list(CUBE_TRI_POS)
    pos[4] = float("nan")
    m, d = gltf_model(positions=pos)
    c.invalid("nan_position.glb", glb_bytes(m, d), r"error: accessor 0 \(POSITION of mesh 0 primitive 0\): element 1 has a non-finite y coordinate \(NaN\)")
    pos[4] = float("inf")
    m, d = gltf_model(positions=pos)
    c.invalid("inf_position.gltf", gltf_text(m, d), r"error: accessor 0 .*element 1 .*\(Inf\)")
    m, d = gltf_model(nodes=[{"mesh": 0, "scale": [1e200, 1, 1]}])
    c.invalid("scale_1e200.glb", glb_bytes(m, d), r"error: node 0, mesh 0 primitive 0: vertex 0 is transformed to x = -1e\+200, beyond the coordinate limit")
    m, d = gltf_model(nodes=[{"mesh": 0, "scale": [1e300, 1e300, 1e300]}, ])
    c.invalid("scale_1e300.gltf", gltf_text(m, d), r"error: node 0, mesh 0 primitive 0: vertex 0 .*coordinate limit")
    m, d = gltf_model(nodes=[{"mesh": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float("nan"), 0, 0, 1]}])
    text = gltf_text(m, d).replace(b"NaN", b"1e999")  # JSON has no NaN: 1e999 reads as inf
    c.invalid("matrix_inf.gltf", text, r"error: (node 0: its transform .* not finite|not a readable glTF)")
    m, d = gltf_model(nodes=[{"mesh": 0, "children": [0]}])
    c.invalid("node_cycle.glb", glb_bytes(m, d), r"error: (node 0: the node hierarchy is deeper|not a readable glTF)")
    m, d = gltf_model(mode=1)
    c.invalid("lines_mode.glb", glb_bytes(m, d), r"error: mesh 0 primitive 0: mode 1 is not supported")
    m, d = gltf_model(drop_position=True)
    c.invalid("no_position.glb", glb_bytes(m, d), r"error: (mesh 0 primitive 0 has no POSITION|not a readable glTF)")
    m, d = gltf_model(indices=[0, 1, 99])
    c.invalid("index_out_of_range.glb", glb_bytes(m, d), r"error: mesh 0 primitive 0: triangle 0 uses index 99")
    m, d = gltf_model(indices=CUBE_TRI_IDX[:-1])
    c.invalid("indices_not_triples.glb", glb_bytes(m, d), r"error: mesh 0 primitive 0 has 35 indices")
    m, d = gltf_model(byte_stride=8)
    c.invalid("stride_too_small.gltf", gltf_text(m, d), r"error: (accessor 0 .*byteStride|not a readable glTF)")
    m, d = gltf_model(sparse=True)
    c.invalid("sparse.glb", glb_bytes(m, d), r"error: (accessor 0 .*sparse|not a readable glTF)")
    m, d = gltf_model(pos_type="VEC2", position_count=12)
    c.invalid("position_vec2.glb", glb_bytes(m, d), r"error: accessor 0 .*VEC3 of FLOAT")
    m, d = gltf_model(idx_component=5126)
    c.invalid("float_indices.glb", glb_bytes(m, d), r"error: (accessor 1 .*unsigned|not a readable glTF)")
    m, d = gltf_model(mesh_index=5)
    c.invalid("missing_mesh.glb", glb_bytes(m, d), r"error: (node 0 refers to mesh 5|not a readable glTF)")
    m, d = gltf_model(scenes=[{"nodes": [7]}])
    c.invalid("missing_node.glb", glb_bytes(m, d), r"error: (the scene refers to node 7|not a readable glTF)")
    m, d = gltf_model(nodes=[{}])
    c.invalid("no_triangles.glb", glb_bytes(m, d), r"error: no triangles in the scene")
    c.invalid("bad_json.gltf", b'{"asset": {"version": "2.0"}, "meshes": [', r"error: not a readable glTF")
    c.invalid("not_json.gltf", bytes(rng.getrandbits(8) for _ in range(4096)), r"error: not a readable glTF")
    m, d = gltf_model()
    c.invalid("bad_magic.glb", glb_bytes(m, d, magic=b"gLTF"), r"error: not a readable glTF")
    c.invalid("truncated.glb", glb_bytes(m, d, truncate=100), r"error: not a readable glTF")
    # tinygltf throws std::out_of_range on this one (found by fuzz_gltf): still exit 2.
    c.invalid("empty_buffer_with_bin_chunk.glb", glb_bytes({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 0}]},
                                                           struct.pack("<f", 1.0)),
              r"error: not a readable glTF file: the glTF loader failed")
    c.invalid("empty.glb", b"", r"error: not a readable glTF")
    m, d = gltf_model(buffer_length=1 << 40)
    c.invalid("buffer_length_1T.glb", glb_bytes(m, d), r"error: not a readable glTF")
    m, d = gltf_model(extra_buffer_views=None)
    m["bufferViews"][0]["byteOffset"] = 1 << 40
    c.invalid("view_offset_1T.gltf", gltf_text(m, d), r"error: (accessor 0 .*buffer view 0 .*outside|not a readable glTF)")
    m, d = gltf_model(buffer_uri="fifo_buffer.bin")
    c.invalid("buffer_fifo.gltf", gltf_text(m, d), r"error: not a readable glTF.*FIFO")
    m, d = gltf_model(buffer_uri="a_directory")
    c.invalid("buffer_directory.gltf", gltf_text(m, d), r"error: not a readable glTF")
    m, d = gltf_model(buffer_uri="/dev/zero")
    c.invalid("buffer_dev_zero.gltf", gltf_text(m, d), r"error: not a readable glTF.*(is a character device|File not found : /dev/zero)")
    m, d = gltf_model(buffer_uri="missing.bin")
    c.invalid("buffer_missing.gltf", gltf_text(m, d), r"error: not a readable glTF")
    m, d = gltf_model(images=[{"uri": "fifo_buffer.bin"}])
    c.add("image_fifo.gltf", gltf_text(m, d), {"default": {"exit": None, "message": ""}})
    m, d = gltf_model()
    m["nodes"][0]["name"] = "\x1b[2J" + "n" * 100000
    c.add("long_node_name.glb", glb_bytes(m, d), {"default": OK})

    # --- STL, PLY, OFF ---
    c.add("cube.stl", stl_binary(header=b"solid cube, but binary"), {"default": OK})
    c.add("cube_ascii.STL", stl_ascii(), {"default": OK})
    c.add("cube.ply", ply_binary_big(), {"default": OK})
    c.add("cube.off", off_text(keyword="COFF"), {"default": OK})
    c.invalid("empty.stl", b"", r"error: not an STL file")
    c.invalid("truncated.stl", stl_binary()[:-7], r"error: binary STL truncated: bytes 80-83 announce 12 facets")
    c.invalid("count_2e9.stl", stl_binary(count=2000000000), r"error: binary STL truncated: bytes 80-83 announce 2000000000")
    nan = bytearray(stl_binary())
    nan[84 + 50 * 3 + 16:84 + 50 * 3 + 20] = struct.pack("<f", float("nan"))
    c.invalid("nan.stl", bytes(nan), r"error: facet 3: vertex has a non-finite y coordinate \(NaN\)")
    c.invalid("ascii_garbage.stl", "solid x\nfacet normal 0 0 1\nouter loop\nvertex 1 2\n",
              r"\.stl:4: error: (vertex coordinate|the file ends)")
    c.invalid("count_1e7.ply", ply_binary_big()[:200].replace(b"vertex 8", b"vertex 10000000"),
              r"error: element 'vertex' announces 10000000 items")
    big = ply_binary_big(count_type="uint")
    at = big.index(b"end_header\n") + 11 + 8 * 24
    c.invalid("list_2e31.ply", big[:at] + struct.pack(">I", 2 ** 31) + big[at + 4:],
              r"error: face 0: face has 2147483648 vertices")
    c.invalid("point_cloud.ply", "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
              "property float z\nend_header\n0 0 0\n1 1 1\n", r"error: the file defines no mesh")
    c.invalid("negative_index.off", off_text(faces=[(0, 1, -1)]), r"\.off:11: error: face refers to vertex -1")
    c.invalid("nonmanifold.off", off_text(faces=[(0, 1, 2), (1, 0, 3), (0, 1, 4)]),
              r"\.off:13: error: non-manifold edge: shared by 3 faces \(lines 11, 12, 13\)")
    c.invalid("counts_1e12.off", off_text(counts=(10 ** 12, 6)), r"\.off:2: error: the file announces 1000000000000 vertices")
    c.invalid("counts_beyond.off", off_text(counts=(8, 10 ** 7)), r"\.off:2: error: .*but only \d+ bytes follow")
    moebius_v, moebius_f = [], []
    for i in range(8):
        u = 2 * math.pi * i / 8
        for w in (-0.3, 0.3):
            moebius_v.append(((1 + w * math.cos(u / 2)) * math.cos(u), (1 + w * math.cos(u / 2)) * math.sin(u),
                              w * math.sin(u / 2)))
    for i in range(8):
        a, b = 2 * i, 2 * i + 1
        cc, d = (2 * i + 2, 2 * i + 3) if i < 7 else (1, 0)
        moebius_f += [(a, cc, d), (a, d, b)]
    c.invalid("moebius.off", off_text(moebius_f, moebius_v), r"\.off:\d+: error: the surface is not orientable")

    # --- special files and names ---
    fifo = os.path.join(c.root, "fifo_buffer.bin")
    if not os.path.exists(fifo):
        os.mkfifo(fifo)
    c.invalid("fifo.obj", None, r"fifo_buffer\.bin: error: is a FIFO \(named pipe\), not an? ", path="fifo_buffer.bin")
    os.makedirs(os.path.join(c.root, "a_directory"), exist_ok=True)
    c.invalid("directory.obj", None, r"error: is a directory", path="a_directory")
    c.invalid("dev_zero.obj", None, r"/dev/zero: error: is a character device", path="/dev/zero")
    c.invalid("missing.obj", None, r"missing\.obj: error: no such file")
    c.add("cube_target.obj", CUBE, {"default": OK})
    link = os.path.join(c.root, "symlink_cube.obj")
    if not os.path.lexists(link):
        os.symlink("cube_target.obj", link)
    c.add("symlink_cube.obj", None, {"default": OK})
    dangling = os.path.join(c.root, "dangling.obj")
    if not os.path.lexists(dangling):
        os.symlink("does_not_exist.obj", dangling)
    c.invalid("dangling.obj", None, r"dangling\.obj: error: no such file")
    c.invalid("long_name", None, r"error: (no such file|cannot open)", path="x" * 100000 + ".obj")
    c.invalid("control_name", None, r"\\x1b\[31m.*error: no such file", path="\x1b[31mred.obj")

    # --- outputs (the runner sets these up; "output" says how) ---
    for name, setup, code, message in [
        ("out_is_input", "input", 1, r"is the input file"),
        ("out_hardlink_to_input", "hardlink", 1, r"is the input file"),
        ("out_fifo", "fifo", 3, r"is a FIFO"),
        ("out_directory", "directory", 3, r"is a directory"),
        ("out_dev_null", "devnull", 3, r"is a character device"),
        ("out_dangling_link", "dangling", 3, r"symbolic link to .*does not exist"),
        ("out_missing_dir", "missingdir", 3, r"does not exist"),
        ("out_symlink", "symlink", 0, r""),
        ("report_same_as_out", "report_same", 1, r"name the same file"),
        ("report_missing_dir", "report_missingdir", 3, r"does not exist"),
        ("preview_is_input", "preview_input", 1, r"is the input file"),
    ]:
        c.add(name, None, {"default": {"exit": code, "message": message}}, path="cube_target.obj", kind="output:" + setup)

    # --- limit queries ---
    for name, text, message in [
        ("q_nan.txt", "0 0 nan 0.5\n", r"q_nan\.txt:1: error: .*outside"),
        ("q_inf.txt", "0 0 0.5 inf\n", r":1: error: .*outside"),
        ("q_face_huge.txt", "99999999999 0 0.5 0.5\n", r":1: error: .*not a non-negative integer"),
        ("q_face_missing.txt", "\n\n6 0 0.5 0.5\n", r":3: error: no face 6"),
        ("q_negative.txt", "-1 0 0.5 0.5\n", r":1: error: "),
        ("q_fields.txt", "0 0\n", r":1: error: .*2 fields"),
        ("q_long_token.txt", "0 0 0.5 " + "9" * 300000 + "\n", r":1: error: .*\.\.\."),
        ("q_nul.txt", "0 0\x00 0.5 0.5\n", r":1: error: .*\\x00"),
        ("q_subface.txt", "0 3 0.5 0.5\n", r":1: error: .*sub-face"),
    ]:
        c.add(name, text, {"limit": {"exit": 2, "message": message}}, kind="queries")
    c.add("q_fifo", None, {"limit": {"exit": 2, "message": r"is a FIFO"}}, path="fifo_buffer.bin", kind="queries")

    c.write_manifest()
    print("%d cases in %s" % (len(c.cases), c.root))


if __name__ == "__main__":
    main()
