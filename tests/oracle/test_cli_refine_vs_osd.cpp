// `subd2nurbs refine` end to end: the OBJ it writes for corpus shapes matches OpenSubdiv's
// refinement of the same shape (positions and faces, through the explicit origin mapping),
// and carries the tags (sharpness, holes) of the refined level.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "io/obj_reader.h"
#include "osd_reference.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;
namespace fs = std::filesystem;

namespace {

class CliRefine : public ::testing::TestWithParam<std::string> {};

}  // namespace

TEST_P(CliRefine, OutputMatchesOpenSubdiv) {
  const int levels = 2;
  const std::string in = std::string(SUBD2NURBS_CORPUS_DIR) + "/" + GetParam() + ".obj";
  const fs::path out = fs::temp_directory_path() / ("subd2nurbs_cli_" + GetParam() + ".obj");
  const std::string cmd = std::string(SUBD2NURBS_CLI) + " refine " + in + " -l " +
                          std::to_string(levels) + " -o " + out.string() + " 2>/dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  LoadedCage written = read_obj(out.string());
  fs::remove(out);
  SubdivLevel written_level = SubdivLevel::from_input(written.input);

  LoadedCage original = read_obj(in);
  OsdRefinement osd = osd_refine(original.input, levels);
  ASSERT_TRUE(osd.refiner);
  Refinement ours = refine_uniform(SubdivLevel::from_input(original.input), levels);
  OsdMapping map = map_to_osd(ours, *osd.refiner);
  const auto& tl = osd.refiner->GetLevel(levels);
  const PolyMesh& m = written_level.mesh;
  ASSERT_EQ(m.num_vertices(), tl.GetNumVertices());
  ASSERT_EQ(m.num_faces(), tl.GetNumFaces());
  std::vector<Point3> base(original.input.positions.begin(), original.input.positions.end());
  const double diag = bbox_diagonal(base);
  double err = 0;
  for (int v = 0; v < m.num_vertices(); ++v)
    for (int k = 0; k < 3; ++k)
      err = std::max(err, std::abs(written.input.positions[v][k] - osd.positions[levels][map.vertex[levels][v]][k]));
  EXPECT_LE(err / diag, 1e-12);
  int bad_faces = 0, bad_holes = 0;
  for (int f = 0; f < m.num_faces(); ++f) {
    auto tv = tl.GetFaceVertices(map.face[levels][f]);
    const int* fv = m.face_vertices(f);
    int shift = 0;
    while (shift < 4 && tv[shift] != map.vertex[levels][fv[0]]) ++shift;
    for (int i = 0; i < 4; ++i) bad_faces += shift == 4 || tv[(shift + i) % 4] != map.vertex[levels][fv[i]];
    bad_holes += static_cast<bool>(written_level.face_hole[f]) != tl.IsFaceHole(map.face[levels][f]);
  }
  EXPECT_EQ(bad_faces, 0);
  EXPECT_EQ(bad_holes, 0);
  int bad_sharp = 0;
  for (int e = 0; e < m.num_edges(); ++e) {
    const int te = tl.FindEdge(map.vertex[levels][m.edge_vertex(e, 0)], map.vertex[levels][m.edge_vertex(e, 1)]);
    bad_sharp += te < 0 || written_level.edge_sharpness[e] != tl.GetEdgeSharpness(te);
  }
  EXPECT_EQ(bad_sharp, 0);
}

// A spread of rules: smooth, boundary rules, semi-sharp uniform and Chaikin creases, corners,
// holes, n-gons, triangles with the smooth-triangle rule, valence 2, high valence.
INSTANTIATE_TEST_SUITE_P(Corpus, CliRefine,
                         ::testing::Values("catmark_cube", "catmark_edgeonly", "catmark_edgenone",
                                           "catmark_chaikin1", "catmark_cubes_semisharp",
                                           "catmark_hole_test2", "catmark_nonquads",
                                           "catmark_smoothtris1", "catmark_val2_interior",
                                           "catmark_pole64", "catmark_torus_creases1",
                                           "catmark_helmet"),
                         [](const auto& info) { return info.param; });
