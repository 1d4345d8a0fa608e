"""Valid but nasty cages (issue #32): scale extremes, thin and tiny parts, unused far vertices,
high valence, big n-gons, non-orientable and flat cages. Each builder returns (vertices, faces)
with 1-based OBJ indices; `obj_text` writes them with every digit (repr)."""
import math

CUBE_V = [(-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
          (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)]
CUBE_F = [(1, 4, 3, 2), (5, 6, 7, 8), (1, 2, 6, 5), (2, 3, 7, 6), (3, 4, 8, 7), (4, 1, 5, 8)]


def obj_text(vertices, faces):
    lines = ["v " + " ".join(repr(float(c)) for c in v) for v in vertices]
    lines += ["f " + " ".join(str(i) for i in f) for f in faces]
    return "\n".join(lines) + "\n"


def box(sx, sy, sz, at=(0.0, 0.0, 0.0)):
    """An axis-aligned box cage of the given full sizes centred at `at` (outward faces)."""
    v = [(at[0] + x * sx / 2, at[1] + y * sy / 2, at[2] + z * sz / 2) for x, y, z in CUBE_V]
    return v, list(CUBE_F)


def cube(size, at=(0.0, 0.0, 0.0)):
    return box(size, size, size, at)


def join(*parts):
    """Several cages in one (vertex indices shifted)."""
    vertices, faces = [], []
    for v, f in parts:
        offset = len(vertices)
        vertices += v
        faces += [tuple(i + offset for i in face) for face in f]
    return vertices, faces


def with_unused(cage, *points):
    v, f = cage
    return v + list(points), f


def bipyramid(n):
    """Two fans of n triangles around the poles (0, 0, +-1): both poles have valence n."""
    v = [(0.0, 0.0, 1.0), (0.0, 0.0, -1.0)]
    v += [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n), 0.0) for k in range(n)]
    f = []
    for k in range(n):
        a, b = 3 + k, 3 + (k + 1) % n
        f.append((1, a, b))
        f.append((2, b, a))
    return v, f


def ngon(n):
    """A single planar n-gon (an open disc)."""
    v = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n), 0.0) for k in range(n)]
    return v, [tuple(range(1, n + 1))]


def prism(n, height=1.0):
    """A prism with n-gon caps and n quad sides (closed, outward)."""
    ring = [(math.cos(2 * math.pi * k / n), math.sin(2 * math.pi * k / n)) for k in range(n)]
    v = [(x, y, 0.0) for x, y in ring] + [(x, y, height) for x, y in ring]
    f = [tuple(range(n, 0, -1)), tuple(range(n + 1, 2 * n + 1))]
    for k in range(n):
        a, b = 1 + k, 1 + (k + 1) % n
        f.append((a, b, b + n, a + n))
    return v, f


def capsule(n):
    """An n-sided capsule: a cylinder of n quads between two rings, a ring of quads on each side
    towards the axis and a fan of n triangles to each pole (poles of valence n)."""
    def ring(r, z):
        return [(r * math.cos(2 * math.pi * k / n), r * math.sin(2 * math.pi * k / n), z) for k in range(n)]
    v = ring(0.7, -1.4) + ring(1.0, -1.0) + ring(1.0, 1.0) + ring(0.7, 1.4) + [(0.0, 0.0, -1.7), (0.0, 0.0, 1.7)]
    south, north = 4 * n + 1, 4 * n + 2
    f = []
    for r in range(3):
        for k in range(n):
            a, b = r * n + 1 + k, r * n + 1 + (k + 1) % n
            f.append((a, b, b + n, a + n))
    for k in range(n):
        a, b = 1 + k, 1 + (k + 1) % n
        f.append((south, b, a))
        a, b = 3 * n + 1 + k, 3 * n + 1 + (k + 1) % n
        f.append((north, a, b))
    return v, f


def moebius(n=16):
    """A Moebius strip of n quads (open, non-orientable)."""
    v = []
    for k in range(n):
        u = 2 * math.pi * k / n
        for w in (-0.3, 0.3):
            v.append(((1 + w * math.cos(u / 2)) * math.cos(u), (1 + w * math.cos(u / 2)) * math.sin(u),
                      w * math.sin(u / 2)))
    f = []
    for k in range(n):
        a, b = 1 + 2 * k, 2 + 2 * k
        if k + 1 < n:
            c, d = 1 + 2 * (k + 1), 2 + 2 * (k + 1)
        else:  # the half twist: the strip's two sides swap
            c, d = 2, 1
        f.append((a, c, d, b))
    return v, f


def klein(nu=12, nv=8):
    """A Klein bottle as a closed quad grid (figure-8 immersion): u wraps with a flip of v."""
    v = []
    for i in range(nu):
        u = 2 * math.pi * i / nu
        for j in range(nv):
            t = 2 * math.pi * j / nv
            r = 2.0
            x = (r + math.cos(u / 2) * math.sin(t) - math.sin(u / 2) * math.sin(2 * t)) * math.cos(u)
            y = (r + math.cos(u / 2) * math.sin(t) - math.sin(u / 2) * math.sin(2 * t)) * math.sin(u)
            z = math.sin(u / 2) * math.sin(t) + math.cos(u / 2) * math.sin(2 * t)
            v.append((x, y, z))

    def idx(i, j):
        if i == nu:  # wrapping around u reflects v: (u + 2 pi, t) = (u, -t)
            return 1 + (-j) % nv
        return 1 + i * nv + j % nv
    f = []
    for i in range(nu):
        for j in range(nv):
            f.append((idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)))
    return v, f


def flat_cube():
    """A unit cube flattened onto z = 0 (every face still there)."""
    v, f = cube(2.0)
    return [(x, y, 0.0) for x, y, _ in v], f


def pillow():
    """Two quads glued along all four edges (opposite orientations): a closed, flat cage."""
    v = [(-1.0, -1.0, 0.0), (1.0, -1.0, 0.0), (1.0, 1.0, 0.0), (-1.0, 1.0, 0.0)]
    return v, [(1, 2, 3, 4), (4, 3, 2, 1)]


def beyond_limit():
    """A unit cube with one coordinate the next double above the limit 1e15."""
    v, f = cube(1.0)
    v[0] = (math.nextafter(1e15, math.inf), v[0][1], v[0][2])
    return v, f


# --- the cases ---------------------------------------------------------------------------------
# kind: what the run must give (tests/nasty/run_nasty.py):
#   solid    STEP and BREP written (exit 0), read back by OCCT valid with `solids` solids of
#            positive volume; `sides` (x, y, z): the volume is the unit cube's times x y z
#            (Catmull-Clark is affine invariant); `same_as`: the volume of that case
#   brep     STEP refused (exit 2, "cannot carry it", no file) after warning `warning`; the BREP
#            written and read back as for solid
#   flat     STEP and BREP written with the flat_part warning, valid, volume zero
#   open     STEP and BREP written, valid, no solid, `faces` > 0
#   heavy    as solid, or the resource guard's refusal (exit 1); timeout: the time class
#   refused  convert exits `exit` with `message` (a regular expression); `info` too when given
# timeout: the ctest TIMEOUT (seconds); label slow for the heavy ones (capsule_1024's whole run
# takes about 5 minutes under load: two conversions of about 60 s at 3.6 GB and the read-backs).
CASES = {
    "scale_1e-9": dict(cage=lambda: cube(1e-9), kind="brep", warning="tiny_part", sides=(1e-9,) * 3, timeout=60),
    "scale_1e-3": dict(cage=lambda: cube(1e-3), kind="solid", sides=(1e-3,) * 3, timeout=60),
    "scale_1e9": dict(cage=lambda: cube(1e9), kind="solid", sides=(1e9,) * 3, timeout=60),
    "thin_1x1e-9x1": dict(cage=lambda: box(1, 1e-9, 1), kind="brep", warning="thin_part", sides=(1, 1e-9, 1),
                          timeout=60),
    "thin_1e8x1e-8x1": dict(cage=lambda: box(1e8, 1e-8, 1), kind="brep", warning="flat_part",
                            sides=(1e8, 1e-8, 1), timeout=60),
    "tiny_cube_2e-6": dict(cage=lambda: cube(2e-6), kind="solid", sides=(2e-6,) * 3, timeout=60),
    "tiny_beside_unit": dict(cage=lambda: join(cube(1.0), cube(1e-12, at=(2.0, 0.0, 0.0))), kind="brep",
                             warning="tiny_part", solids=2, sides=(1, 1, 1), timeout=60),
    "unused_1e6": dict(cage=lambda: with_unused(cube(2.0), (1e6, 0.0, 0.0)), kind="solid", sides=(2, 2, 2),
                       timeout=60),
    "unused_1e9": dict(cage=lambda: with_unused(cube(2.0), (1e9, 1e9, 1e9)), kind="solid", sides=(2, 2, 2),
                       timeout=60),
    "valence_16": dict(cage=lambda: bipyramid(16), kind="solid", timeout=120),
    "valence_64": dict(cage=lambda: bipyramid(64), kind="heavy", timeout=600, slow=True),
    "valence_256": dict(cage=lambda: bipyramid(256), kind="heavy", timeout=900, slow=True),
    "valence_1024": dict(cage=lambda: bipyramid(1024), kind="heavy", timeout=1800, slow=True),
    "ngon_1000": dict(cage=lambda: ngon(1000), kind="heavy", open=True, timeout=600, slow=True),
    "prism_1000": dict(cage=lambda: prism(1000), kind="heavy", timeout=1800, slow=True),
    "capsule_1024": dict(cage=lambda: capsule(1024), kind="heavy", timeout=1800, slow=True),
    "prism_12": dict(cage=lambda: prism(12), kind="solid", timeout=120),
    "moebius": dict(cage=moebius, kind="refused", exit=2, info_exit=2,
                    message=r"moebius\.obj:\d+: error: the surface is not orientable \(like a Moebius strip or a "
                            r"Klein bottle\).*cannot be converted to a closed oriented body", timeout=60),
    "klein": dict(cage=klein, kind="refused", exit=2, info_exit=2,
                  message=r"klein\.obj:\d+: error: the surface is not orientable.*closed oriented body", timeout=60),
    "flat_cube": dict(cage=flat_cube, kind="flat", timeout=60),
    "pillow": dict(cage=pillow, kind="flat", timeout=60),
    "beyond_limit": dict(cage=beyond_limit, kind="refused", exit=2, info_exit=2,
                         message=r"beyond_limit\.obj:1: error: vertex 1 has x = 1000000000000000\.1, "
                                 r"beyond the coordinate limit \+-1e\+15", timeout=60),
    "denormal_1e-320": dict(cage=lambda: cube(1e-320), kind="refused", exit=2,
                            message=r"denormal_1e-320\.obj: error: the cage has size 1\.73e-320 \(bounding-box "
                                    r"diagonal\), below the smallest size converted, 1e-60",
                            info=r"diagonal 1\.73\d*e-320", timeout=60),
}
