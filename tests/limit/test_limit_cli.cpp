// `subd2nurbs limit` end to end: output format and values (compared with the library, whose
// values are checked against OpenSubdiv in test_limit_vs_osd.cpp), bad query lines, exit codes.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "common/run_command.h"
#include "io/temp_dir.h"
#include "limit_test_util.h"

using namespace subd2nurbs;
using namespace subd2nurbs::testing;

namespace {

using Result = CommandResult;

/// Runs `subd2nurbs limit MESH [file]` with `queries` on stdin (or in a file).
Result run_limit(const std::string& mesh, const std::string& queries, bool as_file) {
  TempDir dir;
  {
    std::ofstream q(dir.file("q.txt"));
    q << queries;
  }
  return run_command(quote(SUBD2NURBS_EXE) + " limit " + quote(mesh) +
                     (as_file ? " " + quote(dir.file("q.txt")) : " <" + quote(dir.file("q.txt"))));
}

}  // namespace

TEST(LimitCli, PrintsOneLinePerQueryWithTheLibraryValues) {
  const std::string mesh = limit_corpus_path("catmark_nonquads");
  const LoadedCage cage = read_obj(mesh);
  const LimitEvaluator ev(SubdivLevel::from_input(cage.input), positions_of(cage.input));
  // A quad face and an n-gon's sub-faces, with comments and blank lines in between.
  int quad = -1, ngon = -1;
  for (int f = 0; f < ev.base().mesh.num_faces(); ++f)
    (ev.base().mesh.face_size(f) == 4 ? quad : ngon) = f;
  ASSERT_GE(quad, 0);
  ASSERT_GE(ngon, 0);
  std::ostringstream q;
  q << "# queries\n" << quad << " 0.25 0.5\n\n" << ngon << " 1 0.3 0.6\n" << quad << " 0 1 0\n";
  for (bool as_file : {false, true}) {
    const Result r = run_limit(mesh, q.str(), as_file);
    ASSERT_EQ(r.exit_code, 0) << r.err;
    std::istringstream lines(r.out);
    const LimitSample want[3] = {ev.evaluate(quad, 0, 0.25, 0.5), ev.evaluate(ngon, 1, 0.3, 0.6),
                                 ev.evaluate(quad, 0, 1, 0)};
    std::string line;
    int n = 0;
    while (std::getline(lines, line)) {
      ASSERT_LT(n, 3);
      std::istringstream fields(line);
      std::vector<double> x;
      for (double d; fields >> d;) x.push_back(d);
      ASSERT_EQ(x.size(), 12u) << line;
      const LimitSample& w = want[n];
      for (int k = 0; k < 3; ++k) {
        EXPECT_EQ(x[k], w.p[k]);  // %.17g round-trips doubles exactly
        EXPECT_EQ(x[3 + k], w.normal[k]);
        EXPECT_EQ(x[6 + k], w.du[k]);
        EXPECT_EQ(x[9 + k], w.dv[k]);
      }
      ++n;
    }
    EXPECT_EQ(n, 3);
  }
}

TEST(LimitCli, BadQueryLinesNameTheLineAndExitWith2) {
  const std::string mesh = limit_corpus_path("catmark_nonquads");
  const LoadedCage cage = read_obj(mesh);
  const SubdivLevel level = SubdivLevel::from_input(cage.input);
  int quad = -1, ngon = -1;
  for (int f = 0; f < level.mesh.num_faces(); ++f) (level.mesh.face_size(f) == 4 ? quad : ngon) = f;
  const std::string ok = std::to_string(quad) + " 0.5 0.5\n";
  const std::string n = std::to_string(ngon), qd = std::to_string(quad);
  const std::pair<std::string, std::string> bad[] = {
      {"0 0.5\n", "expected"},
      {"x 0.5 0.5\n", "face index"},
      {qd + " 0.5 nan\n", "outside"},
      {qd + " 1.5 0.5\n", "outside"},
      {qd + " 0.5 abc\n", "not numbers"},
      {"99999 0.5 0.5\n", "no face 99999"},
      {n + " 0.5 0.5\n", "sub-face"},
      {n + " 17 0.5 0.5\n", "no sub-face 17"},
      {qd + " 1 0.5 0.5\n", "no sub-face 1"},
      {"-1 0.5 0.5\n", "face index"},
  };
  for (const auto& [line, why] : bad) {
    SCOPED_TRACE(line);
    const Result r = run_limit(mesh, ok + "# comment\n" + line, true);
    EXPECT_EQ(r.exit_code, 2);
    EXPECT_NE(r.err.find("q.txt:3: error:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find(why), std::string::npos) << r.err;
    EXPECT_EQ(r.out, "");  // nothing printed before every query is known to be good
    const Result s = run_limit(mesh, ok + line, false);
    EXPECT_EQ(s.exit_code, 2);
    EXPECT_NE(s.err.find("<stdin>:2: error:"), std::string::npos) << s.err;
  }
}

TEST(LimitCli, HolesMissingFilesAndUsage) {
  // A face that is a hole has no limit surface: an input error naming the query line.
  const Result hole = run_limit(limit_corpus_path("catmark_hole_test1"), "", false);
  EXPECT_EQ(hole.exit_code, 0);
  const LoadedCage cage = read_obj(limit_corpus_path("catmark_hole_test1"));
  ASSERT_FALSE(cage.input.holes.empty());
  const Result r = run_limit(limit_corpus_path("catmark_hole_test1"),
                             std::to_string(cage.input.holes[0]) + " 0.5 0.5\n", false);
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.err.find("<stdin>:1: error:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("hole"), std::string::npos) << r.err;
  // Missing mesh, missing query file, missing argument.
  EXPECT_EQ(run_limit("/nonexistent.obj", "0 0.5 0.5\n", false).exit_code, 2);
  const Result missing = run_command(quote(SUBD2NURBS_EXE) + " limit " + quote(limit_corpus_path("catmark_cube")) +
                                     " /nonexistent_queries.txt");
  EXPECT_EQ(missing.exit_code, 2);
  EXPECT_NE(missing.err.find("/nonexistent_queries.txt"), std::string::npos);
  EXPECT_EQ(run_command(quote(SUBD2NURBS_EXE) + " limit").exit_code, 1);
}

TEST(CheckCli, WritesTheQualityReportAndUsesTheDocumentedExitCodes) {
  TempDir dir;
  const std::string cube = limit_corpus_path("catmark_cube");
  auto sh = [&](const std::string& args) { return run_command(quote(SUBD2NURBS_EXE) + " " + args); };
  const Result check = sh("check " + quote(cube) + " --json " + quote(dir.file("q.json")));
  ASSERT_EQ(check.exit_code, 0) << check.err;
  EXPECT_NE(check.err.find("quality: deviation from the exact limit max"), std::string::npos);
  // Python reads it; the cube has irregular vertices, so the deviation is positive but small,
  // every shared edge is smooth, and the samples cover every patch.
  const std::string py =
      "import json,sys; r=json.load(open(sys.argv[1])); q=r['quality']; d=q['deviation'];"
      "assert r['format']=='subd2nurbs-quality' and r['version']==1;"
      "assert 0 < d['max'] < 0.05*r['model_size'] and d['max'] <= d['parametric_max'];"
      "n=q['samples_per_side']; k=d['polynomial_patches'];"
      "assert d['samples']>=k*min(n,4)**2+(r['patches']-k)*n**2 and len(q['patch_max'])==r['patches'];"
      "assert q['edges_summary']['crease']==0 and len(q['edges'])==q['edges_summary']['smooth'];"
      "assert q['curvature']['max_k'] < 0";
  EXPECT_EQ(std::system(("python3 -c " + quote(py) + " " + quote(dir.file("q.json"))).c_str()), 0);
  // convert --report carries the same object.
  ASSERT_EQ(sh("convert " + quote(cube) + " -o " + quote(dir.file("c.step")) + " --report " +
               quote(dir.file("r.json")) + " -q")
                .exit_code,
            0);
  const std::string same =
      "import json,sys; a=json.load(open(sys.argv[1]))['quality']; b=json.load(open(sys.argv[2]))['quality'];"
      "assert a['deviation']==b['deviation'] and a['edges']==b['edges'], 'differ'";
  EXPECT_EQ(std::system(("python3 -c " + quote(same) + " " + quote(dir.file("q.json")) + " " +
                         quote(dir.file("r.json")))
                            .c_str()),
            0);
  // Packed or per quad, the same quads are sampled on the faces that hold them: the same
  // surface, so the same deviation (the packed torus is one face, 32 quads).
  const std::string torus = limit_corpus_path("catmark_torus");
  ASSERT_EQ(sh("check " + quote(torus) + " -q --json " + quote(dir.file("tp.json"))).exit_code, 0);
  ASSERT_EQ(sh("check " + quote(torus) + " -q --faces per-quad --json " + quote(dir.file("tq.json"))).exit_code, 0);
  const std::string faces =
      "import json,sys; a=json.load(open(sys.argv[1])); b=json.load(open(sys.argv[2]));"
      "assert a['faces']=={'mode':'packed','total':1} and b['faces']=={'mode':'per-quad','total':32}, (a['faces'], b['faces']);"
      "assert a['patches']==b['patches']==32;"
      "da, db = a['quality']['deviation'], b['quality']['deviation'];"
      "assert da['samples']==db['samples'] and abs(da['parametric_max']-db['parametric_max']) <= 1e-12*a['model_size'];"
      "assert da['parametric_max'] <= 1e-12*a['model_size']";
  EXPECT_EQ(std::system(("python3 -c " + quote(faces) + " " + quote(dir.file("tp.json")) + " " + quote(dir.file("tq.json")))
                            .c_str()),
            0);
  EXPECT_EQ(sh("check " + quote(torus) + " --faces some").exit_code, 1);
  EXPECT_EQ(sh("check /nonexistent.obj").exit_code, 2);
  EXPECT_EQ(sh("check " + quote(cube) + " --samples 1").exit_code, 1);
  EXPECT_EQ(sh("check " + quote(cube) + " --json /nonexistent_dir/q.json").exit_code, 3);
}
