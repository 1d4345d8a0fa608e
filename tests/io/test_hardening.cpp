// Hostile inputs and outputs at the io layer (issue #14): special files refused before they
// can block, byte-order marks, counts bounded by the bytes present, instancing caps, names made
// printable, symbolic-link and staged-output semantics.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <cstring>
#include <filesystem>
#include <string>

#include "core/mesh/validate.h"
#include "io/atomic_file.h"
#include "io/gltf_reader.h"
#include "io/input_error.h"
#include "io/input_file.h"
#include "io/obj_reader.h"
#include "io/temp_dir.h"

using namespace subd2nurbs;
using subd2nurbs::testing::read_text;
using subd2nurbs::testing::TempDir;

namespace {

const char* kCube =
    "v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\nv -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

std::vector<std::string> sorted_entries(const TempDir& dir) {
  std::vector<std::string> e = dir.entries();
  std::sort(e.begin(), e.end());
  return e;
}

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

}  // namespace

TEST(InputFile, FifoIsRefusedWithoutBlocking) {
  TempDir dir;
  const std::string fifo = dir.file("pipe.obj");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  const auto t0 = std::chrono::steady_clock::now();
  const std::string m = message_of([&] { read_obj(fifo); });
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(5));
  EXPECT_NE(m.find("is a FIFO"), std::string::npos) << m;
}

TEST(InputFile, DirectoryAndDeviceAreNamed) {
  TempDir dir;
  EXPECT_NE(message_of([&] { read_obj(dir.path().string()); }).find("is a directory"), std::string::npos);
  EXPECT_NE(message_of([&] { read_obj("/dev/zero"); }).find("is a character device"), std::string::npos);
  EXPECT_NE(message_of([&] { read_obj(dir.file("none.obj")); }).find("no such file"), std::string::npos);
}

TEST(InputFile, PrintableEscapesAndShortens) {
  EXPECT_EQ(printable(std::string("a\0b\x1b[", 5)), "a\\x00b\\x1b[");
  const std::string long_name(100000, 'x');
  const std::string p = printable(long_name, 90);
  EXPECT_LT(p.size(), 140u);
  EXPECT_NE(p.find("(100000 bytes)"), std::string::npos) << p;
  // An InputError names the file printably.
  const InputError e(std::string("bad\nname", 8), 3, "message");
  EXPECT_EQ(std::string(e.what()), "bad\\x0aname:3: message");
}

TEST(ObjReader, Utf8ByteOrderMarkIsSkipped) {
  const LoadedCage cage = parse_obj(std::string("\xEF\xBB\xBF") + kCube, "bom.obj");
  EXPECT_EQ(cage.input.num_vertices(), 8);
  EXPECT_EQ(cage.input.num_faces(), 6);
  EXPECT_TRUE(cage.diagnostics.empty());
  EXPECT_EQ(cage.input.face_indices[0], 0);  // not shifted by a lost first vertex
}

TEST(ObjReader, Utf16IsRefusedAtLine1) {
  std::string utf16 = "\xFF\xFE";
  for (const char* c = kCube; *c; ++c) utf16 += std::string(1, *c) + '\0';
  try {
    parse_obj(utf16, "u.obj");
    FAIL() << "accepted UTF-16";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_NE(e.message().find("UTF-16"), std::string::npos) << e.what();
  }
  // Without a byte-order mark too.
  EXPECT_NE(message_of([&] { parse_obj(utf16.substr(2), "u.obj"); }).find("UTF-16"), std::string::npos);
}

TEST(ObjReader, CoordinateBeyondTheLimitNamesTheLine) {
  std::string text = kCube;
  text.replace(text.find("v 1 1 1"), 7, "v 1e200 1 1");
  const LoadedCage cage = parse_obj(text, "big.obj");
  try {
    validate_cage(cage);
    FAIL() << "accepted 1e200";
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 7);
    ASSERT_TRUE(e.code().has_value());
    EXPECT_EQ(*e.code(), MeshErrorCode::CoordinateOutOfRange);
  }
  // Just inside the limit is accepted.
  text = kCube;
  text.replace(text.find("v 1 1 1"), 7, "v 1e15 1 1");
  EXPECT_NO_THROW(validate_cage(parse_obj(text, "ok.obj")));
}

TEST(ObjReader, FaceSizeAndValenceLimitsNameTheElement) {
  std::string big;
  for (int k = 0; k < kMaxFaceSize + 1; ++k) big += "v " + std::to_string(k) + " " + std::to_string(k % 7) + " 0\n";
  big += "f";
  for (int k = 1; k <= kMaxFaceSize + 1; ++k) big += " " + std::to_string(k);
  big += "\n";
  try {
    validate_cage(parse_obj(big, "big.obj"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), kMaxFaceSize + 2);
    EXPECT_EQ(*e.code(), MeshErrorCode::FaceTooLarge);
  }
  std::string fan = "v 0 0 1\n";
  const int n = kMaxValence + 1;
  for (int k = 0; k < n; ++k) fan += "v " + std::to_string(k) + " " + std::to_string(k * k % 11) + " 0\n";
  for (int k = 0; k < n; ++k) fan += "f 1 " + std::to_string(2 + k) + " " + std::to_string(2 + (k + 1) % n) + "\n";
  try {
    validate_cage(parse_obj(fan, "fan.obj"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.line(), 1);
    EXPECT_EQ(*e.code(), MeshErrorCode::ValenceTooHigh);
  }
}

TEST(AtomicFile, SymbolicLinkTargetIsReplacedAndTheLinkKept) {
  TempDir dir;
  const std::string target = dir.write("target.txt", "old\n");
  const std::string link = dir.file("link.txt");
  ASSERT_EQ(::symlink("target.txt", link.c_str()), 0);
  write_file_atomically(link, [](std::ostream& out) { out << "new\n"; });
  EXPECT_TRUE(std::filesystem::is_symlink(link));
  EXPECT_EQ(read_text(target), "new\n");
  EXPECT_EQ(sorted_entries(dir), (std::vector<std::string>{"link.txt", "target.txt"}));
}

TEST(AtomicFile, DanglingLinkFifoAndDeviceAreRefused) {
  TempDir dir;
  const std::string dangling = dir.file("dangling.txt");
  ASSERT_EQ(::symlink("nowhere/x.txt", dangling.c_str()), 0);
  EXPECT_THROW(write_file_atomically(dangling, [](std::ostream& out) { out << "x"; }), WriteError);
  const std::string fifo = dir.file("pipe.txt");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(message_of([&] { write_file_atomically(fifo, [](std::ostream& out) { out << "x"; }); }).find("FIFO"),
            std::string::npos);
  EXPECT_NE(message_of([&] { resolve_output_path("/dev/null"); }).find("character device"), std::string::npos);
  EXPECT_EQ(sorted_entries(dir), (std::vector<std::string>{"dangling.txt", "pipe.txt"}));
}

TEST(AtomicFile, StagedFilesChangeNothingUntilCommitted) {
  TempDir dir;
  const std::string a = dir.write("a.txt", "A\n"), b = dir.write("b.txt", "B\n");
  {
    StagedFile sa(a), sb(b);
    sa.write([](std::ostream& out) { out << "new A\n"; });
    sb.write([](std::ostream& out) { out << "new B\n"; });
    EXPECT_EQ(read_text(a), "A\n");
    EXPECT_EQ(dir.entries().size(), 4u);  // two temporaries beside the two files
    sa.commit();
    // sb is destroyed without commit: b keeps its content, its temporary is removed.
  }
  EXPECT_EQ(read_text(a), "new A\n");
  EXPECT_EQ(read_text(b), "B\n");
  EXPECT_EQ(sorted_entries(dir), (std::vector<std::string>{"a.txt", "b.txt"}));
  EXPECT_TRUE(same_file(a, a));
  EXPECT_FALSE(same_file(a, b));
}

// --- glTF ---------------------------------------------------------------------------------

namespace {

/// A one-triangle glTF whose POSITION accessor claims `count` elements.
std::string triangle_gltf(const std::string& count, const std::string& nodes = R"([{"mesh": 0}])") {
  // 3 floats x 3 vertices = 36 bytes, base64 of (0,0,0),(1,0,0),(0,1,0).
  return R"({"asset": {"version": "2.0"}, "buffers": [{"byteLength": 36, "uri": "data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}],
 "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}],
 "accessors": [{"bufferView": 0, "componentType": 5126, "type": "VEC3", "count": )" + count + R"(}],
 "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": )" + nodes + R"(, "scenes": [{"nodes": [0]}], "scene": 0})";
}

}  // namespace

TEST(GltfReader, ValidTriangleReads) {
  const LoadedCage cage = parse_gltf(triangle_gltf("3"), "t.gltf", false, ".");
  EXPECT_EQ(cage.input.num_faces(), 1);
}

TEST(GltfReader, CountBeyondTheBytesPresentIsRefusedBeforeAllocating) {
  const std::string m = message_of([] { parse_gltf(triangle_gltf("400000000"), "t.gltf", false, "."); });
  EXPECT_NE(m.find("accessor 0 (POSITION of mesh 0 primitive 0): count 400000000 needs more bytes"),
            std::string::npos) << m;
}

TEST(GltfReader, InstanceExpansionIsCappedNamingTheNode) {
  std::string nodes = "[";
  for (int i = 0; i < 27; ++i) nodes += R"({"children": [)" + std::to_string(i + 1) + ", " + std::to_string(i + 1) + "]},";
  nodes += R"({"mesh": 0}])";
  const auto t0 = std::chrono::steady_clock::now();
  const std::string m = message_of([&] { parse_gltf(triangle_gltf("3", nodes), "t.gltf", false, "."); });
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(20));
  EXPECT_NE(m.find("the scene expands to more than 100000 node instances"), std::string::npos) << m;
  EXPECT_NE(m.find("node "), std::string::npos) << m;
}

TEST(GltfReader, SmallerLimitsCapExactlyAtTheirValues) {
  // Node 0 has n children, each an instance of the one-triangle mesh moved apart: 1 + n node
  // instances, n triangles, 3n vertices.
  const auto children = [](int n) {
    std::string nodes = R"([{"children": [)";
    for (int i = 1; i <= n; ++i) nodes += (i > 1 ? ", " : "") + std::to_string(i);
    nodes += "]}";
    for (int i = 1; i <= n; ++i) nodes += R"(, {"mesh": 0, "translation": [)" + std::to_string(10 * i) + ", 0, 0]}";
    return nodes + "]";
  };
  GltfLimits limits;
  limits.node_instances = 5;
  EXPECT_EQ(parse_gltf(triangle_gltf("3", children(4)), "t.gltf", false, ".", limits).input.num_faces(), 4);
  std::string m = message_of([&] { parse_gltf(triangle_gltf("3", children(5)), "t.gltf", false, ".", limits); });
  EXPECT_NE(m.find("node 5: the scene expands to more than 5 node instances"), std::string::npos) << m;
  limits.node_instances = 100;
  limits.instanced_triangles = 9;  // vertices: 3 per instance
  EXPECT_EQ(parse_gltf(triangle_gltf("3", children(3)), "t.gltf", false, ".", limits).input.num_faces(), 3);
  m = message_of([&] { parse_gltf(triangle_gltf("3", children(4)), "t.gltf", false, ".", limits); });
  EXPECT_NE(m.find("node 4: instancing mesh 0 primitive 0 here brings the scene to more than 9 vertices"),
            std::string::npos) << m;
}

TEST(GltfReader, Utf8ByteOrderMarkIsSkippedAndUtf16Refused) {
  EXPECT_EQ(parse_gltf("\xEF\xBB\xBF" + triangle_gltf("3"), "t.gltf", false, ".").input.num_faces(), 1);
  EXPECT_NE(message_of([] { parse_gltf("\xFF\xFE{", "t.gltf", false, "."); }).find("UTF-16"), std::string::npos);
}
