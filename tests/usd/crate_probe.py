#!/usr/bin/python3
"""An independent reader of USD crate (usdc) files, written in Python from the format's
description (OpenUSD's crateFile.cpp / integerCoding.cpp), used by the tests as an oracle for
the C++ reader: it prints, per Mesh attribute it finds, the element counts. Only what the tests
need: version >= 0.4 structural sections, int / float / vec arrays (compressed or not)."""
import struct
import sys

import lz4.block


def fast_decompress(buf, size):
    if buf[0] == 0:
        return lz4.block.decompress(bytes(buf[1:]), uncompressed_size=size)
    out, at = b"", 1
    for _ in range(buf[0]):
        (n,) = struct.unpack_from("<i", buf, at)
        out += lz4.block.decompress(bytes(buf[at + 4:at + 4 + n]), uncompressed_size=size - len(out))
        at += 4 + n
    return out


def decode_ints(data, count, width):
    sfmt = {4: ("<i", "<b", "<h"), 8: ("<q", "<h", "<i")}[width]
    (common,) = struct.unpack_from(sfmt[0], data, 0)
    codes = width
    vals = codes + (count * 2 + 7) // 8
    out, prev = [], 0
    for i in range(count):
        code = (data[codes + i // 4] >> (2 * (i % 4))) & 3
        if code == 0:
            d = common
        else:
            f = sfmt[code] if code < 3 else sfmt[0]
            (d,) = struct.unpack_from(f, data, vals)
            vals += struct.calcsize(f)
        prev += d
        out.append(prev)
    return out


class Crate:
    def __init__(self, data):
        self.d = data
        assert data[:8] == b"PXR-USDC"
        self.minor = data[9]
        (toc,) = struct.unpack_from("<Q", data, 16)
        (n,) = struct.unpack_from("<Q", data, toc)
        self.sec = {}
        for i in range(n):
            o = toc + 8 + 32 * i
            name = data[o:o + 16].rstrip(b"\0").decode()
            self.sec[name] = struct.unpack_from("<qq", data, o + 16)
        at = self.sec["TOKENS"][0]
        n, raw, comp = struct.unpack_from("<QQQ", data, at)
        self.tokens = fast_decompress(data[at + 24:at + 24 + comp], raw).split(b"\0")[:n]
        at = self.sec["FIELDS"][0]
        (n,) = struct.unpack_from("<Q", data, at)
        names, at = self.cints(at + 8, n, 4)
        (size,) = struct.unpack_from("<Q", data, at)
        reps = fast_decompress(data[at + 8:at + 8 + size], 8 * n)
        self.fields = [(self.tokens[names[i]].decode(), struct.unpack_from("<Q", reps, 8 * i)[0]) for i in range(n)]
        at = self.sec["FIELDSETS"][0]
        (n,) = struct.unpack_from("<Q", data, at)
        self.fieldsets, _ = self.cints(at + 8, n, 4)
        at = self.sec["PATHS"][0]
        npaths, nenc = struct.unpack_from("<QQ", data, at)
        idx, at = self.cints(at + 16, nenc, 4)
        elem, at = self.cints(at, nenc, 4)
        jumps, at = self.cints(at, nenc, 4)
        self.paths = [None] * npaths
        self.build_paths(idx, elem, jumps)
        at = self.sec["SPECS"][0]
        (n,) = struct.unpack_from("<Q", data, at)
        p, at = self.cints(at + 8, n, 4)
        f, at = self.cints(at, n, 4)
        t, at = self.cints(at, n, 4)
        self.specs = list(zip(p, f, t))

    def cints(self, at, n, width):
        (size,) = struct.unpack_from("<Q", self.d, at)
        raw = fast_decompress(self.d[at + 8:at + 8 + size], width + (2 * n + 7) // 8 + width * n)
        return decode_ints(raw, n, width), at + 8 + size

    def build_paths(self, idx, elem, jumps):
        todo = [(0, None)]
        while todo:
            cur, parent = todo.pop()
            while True:
                if parent is None:
                    self.paths[idx[cur]] = ""
                else:
                    tok = self.tokens[abs(elem[cur])].decode()
                    self.paths[idx[cur]] = parent + ("." if elem[cur] < 0 else "/") + tok
                j = jumps[cur]
                if j > 0 or j == -1:
                    if j > 0:
                        todo.append((cur + j, parent))
                    parent = self.paths[idx[cur]]
                elif j != 0:
                    break
                cur += 1

    def array(self, rep):
        typ, payload = (rep >> 48) & 0xFF, rep & ((1 << 48) - 1)
        if payload == 0:
            return []
        at = payload
        if self.minor < 7:
            (n,) = struct.unpack_from("<I", self.d, at)
            at += 4
        else:
            (n,) = struct.unpack_from("<Q", self.d, at)
            at += 8
        comps = {3: 1, 8: 1, 24: 3, 20: 2}[typ]
        if typ == 3 and rep & (1 << 61) and n >= 16:
            return self.cints(at, n, 4)[0]
        if typ == 8 and rep & (1 << 61) and n >= 16:
            code = self.d[at]
            if code == ord("i"):
                return self.cints(at + 1, n, 4)[0]
            (lut,) = struct.unpack_from("<I", self.d, at + 1)
            table = struct.unpack_from("<%df" % lut, self.d, at + 5)
            return [table[i] for i in self.cints(at + 5 + 4 * lut, n, 4)[0]]
        fmt = "<%d%s" % (n * comps, "i" if typ == 3 else "f")
        return list(struct.unpack_from(fmt, self.d, at))

    def attributes(self):
        """(path, default value) of every attribute spec with an int or float array default."""
        for p, fs, t in self.specs:
            if t != 1:
                continue
            i = fs
            while self.fieldsets[i] & 0xFFFFFFFF != 0xFFFFFFFF:
                name, rep = self.fields[self.fieldsets[i]]
                if name == "default" and rep >> 63 and ((rep >> 48) & 0xFF) in (3, 8, 24):
                    yield self.paths[p], self.array(rep)
                i += 1


if __name__ == "__main__":
    crate = Crate(open(sys.argv[1], "rb").read())
    for path, value in crate.attributes():
        print(path, len(value))
