// Writing STEP / IGES / BREP and reading them back: the shape survives, OCCT's global
// settings are restored, and a failed write leaves nothing behind.
#include <gtest/gtest.h>

#include <Interface_Static.hxx>
#include <STEPControl_Controller.hxx>
#include <TopoDS_Shape.hxx>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

#include "converter/occt/brep_builder.h"
#include "converter/occt/shape_check.h"
#include "converter/occt/writers.h"
#include "io/input_error.h"
#include "occt/synthetic_patch_sets.h"

namespace subd2nurbs::occt {
namespace {

namespace fs = std::filesystem;

class Exchange : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("subd2nurbs_occt_" + std::to_string(::getpid()) + "_" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::string path(const std::string& name) const { return (dir_ / name).string(); }
  std::set<std::string> listing() const {
    std::set<std::string> names;
    for (const auto& entry : fs::directory_iterator(dir_)) names.insert(entry.path().filename());
    return names;
  }
  static std::string slurp(const std::string& file) {
    std::ifstream in(file);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  fs::path dir_;
};

TEST(FormatFromPath, KnowsTheExtensionsInAnyCase) {
  EXPECT_EQ(format_from_path("a.step"), Format::Step);
  EXPECT_EQ(format_from_path("dir.x/a.STP"), Format::Step);
  EXPECT_EQ(format_from_path("a.Iges"), Format::Iges);
  EXPECT_EQ(format_from_path("a.igs"), Format::Iges);
  EXPECT_EQ(format_from_path("/tmp/a.BREP"), Format::Brep);
  EXPECT_THROW(format_from_path("a.obj"), std::invalid_argument);
  EXPECT_THROW(format_from_path("step"), std::invalid_argument);
  EXPECT_THROW(format_from_path("dir.step/file"), std::invalid_argument);
}

// Round trips of the unit cube (six faces keep the STEP and IGES runs fast).
TEST_F(Exchange, RoundTripsKeepFacesAreaAndValidity) {
  const BrepResult built = build_brep(testing::unit_cube());
  ASSERT_TRUE(built.valid) << built.check_message;
  const ShapeSummary before = summarize(built.shape);

  struct Case {
    std::string name;
    Format format;
    StepSchema schema;
    const char* schema_text;  // expected in the STEP header, or nullptr
  };
  const Case cases[] = {
      {"cube_ap214.step", Format::Step, StepSchema::AP214, "AUTOMOTIVE_DESIGN"},
      {"cube_ap242.stp", Format::Step, StepSchema::AP242, "AP242_MANAGED_MODEL_BASED_3D_ENGINEERING"},
      {"cube.igs", Format::Iges, StepSchema::AP214, nullptr},
      {"cube.brep", Format::Brep, StepSchema::AP214, nullptr},
  };
  std::set<std::string> expected_files;
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    ASSERT_EQ(format_from_path(c.name), c.format);
    write_shape(built.shape, path(c.name), c.format, c.schema);
    expected_files.insert(c.name);
    if (c.schema_text != nullptr) {
      const std::string text = slurp(path(c.name));
      EXPECT_NE(text.find(c.schema_text), std::string::npos);
      // Flat: no assembly structure, one product.
      EXPECT_EQ(text.find("NEXT_ASSEMBLY_USAGE_OCCURRENCE"), std::string::npos);
    }

    const TopoDS_Shape back = read_shape(path(c.name));
    const ShapeSummary after = summarize(back);
    EXPECT_TRUE(after.valid) << after.check_message;
    EXPECT_EQ(after.faces, before.faces);
    EXPECT_EQ(after.edges, before.edges);
    EXPECT_EQ(after.free_edges, 0);
    EXPECT_EQ(after.solids, 1);
    EXPECT_NEAR(after.area, before.area, 1e-9 * before.area);
    EXPECT_NEAR(after.volume, before.volume, 1e-9 * before.volume);
  }
  EXPECT_EQ(listing(), expected_files);  // no temporary files left
}

TEST_F(Exchange, SeamedTorusSurvivesBrepAndStep) {
  const BrepResult built = build_brep(testing::bspline_torus(1, 1));
  ASSERT_TRUE(built.valid) << built.check_message;
  const ShapeSummary before = summarize(built.shape);
  for (const std::string name : {"torus.brep", "torus.step"}) {
    SCOPED_TRACE(name);
    write_shape(built.shape, path(name), format_from_path(name));
    const ShapeSummary after = summarize(read_shape(path(name)));
    EXPECT_TRUE(after.valid) << after.check_message;
    EXPECT_EQ(after.faces, 1);
    EXPECT_EQ(after.free_edges, 0);
    EXPECT_NEAR(after.area, before.area, 1e-9 * before.area);
    EXPECT_NEAR(after.volume, before.volume, 1e-9 * before.volume);
  }
}

// BREP text (what the Python module hands FreeCAD) is the .brep file's content without the
// file's "DBRep_DrawableShape" header line, and reads back to the same shape: the unit cube's
// area is 6 and its volume 1.
TEST_F(Exchange, BrepTextIsTheBrepFileAndReadsBack) {
  const BrepResult built = build_brep(testing::bspline_torus(2, 1));
  ASSERT_TRUE(built.valid) << built.check_message;
  const std::string text = brep_text(built.shape);
  write_shape(built.shape, path("torus.brep"), Format::Brep);
  EXPECT_EQ("DBRep_DrawableShape\n" + text, slurp(path("torus.brep")));
  const ShapeSummary before = summarize(built.shape);
  const ShapeSummary after = summarize(read_brep_text(text));
  EXPECT_TRUE(after.valid) << after.check_message;
  EXPECT_EQ(after.faces, 2);
  EXPECT_EQ(after.free_edges, 0);
  EXPECT_NEAR(after.area, before.area, 1e-12 * before.area);

  const ShapeSummary cube = summarize(read_brep_text(brep_text(build_brep(testing::unit_cube()).shape)));
  EXPECT_EQ(cube.faces, 6);
  EXPECT_NEAR(cube.area, 6.0, 1e-9);
  EXPECT_NEAR(cube.volume, 1.0, 1e-9);

  EXPECT_THROW(read_brep_text("not a brep"), ExportError);
  EXPECT_THROW(brep_text(TopoDS_Shape()), ExportError);
}

TEST_F(Exchange, StepWriteRestoresOcctSettings) {
  STEPControl_Controller::Init();  // registers the write.step.* settings
  const std::string assembly = Interface_Static::CVal("write.step.assembly");
  const std::string schema = Interface_Static::CVal("write.step.schema");
  const TopoDS_Shape shape = build_brep(testing::open_patch()).shape;

  // Whatever the caller had set stays set, through a successful and a failed write.
  ASSERT_TRUE(Interface_Static::SetCVal("write.step.assembly", "On"));
  ASSERT_TRUE(Interface_Static::SetCVal("write.step.schema", "AP203"));
  write_shape(shape, path("a.step"), Format::Step, StepSchema::AP242);
  EXPECT_STREQ(Interface_Static::CVal("write.step.assembly"), "On");
  EXPECT_STREQ(Interface_Static::CVal("write.step.schema"), "AP203");
  // ... and the file was written flat in AP242 nevertheless.
  EXPECT_NE(slurp(path("a.step")).find("AP242_MANAGED_MODEL"), std::string::npos);
  EXPECT_EQ(slurp(path("a.step")).find("NEXT_ASSEMBLY_USAGE_OCCURRENCE"), std::string::npos);

  EXPECT_THROW(write_shape(shape, path("missing/b.step"), Format::Step), WriteError);
  EXPECT_STREQ(Interface_Static::CVal("write.step.assembly"), "On");
  EXPECT_STREQ(Interface_Static::CVal("write.step.schema"), "AP203");

  Interface_Static::SetCVal("write.step.assembly", assembly.c_str());
  Interface_Static::SetCVal("write.step.schema", schema.c_str());
  EXPECT_EQ(Interface_Static::CVal("write.step.assembly"), assembly);
}

TEST_F(Exchange, WritingIntoAMissingDirectoryThrowsAndLeavesNothing) {
  const TopoDS_Shape shape = build_brep(testing::unit_cube()).shape;
  for (const std::string name : {"missing/x.step", "missing/x.igs", "missing/x.brep"}) {
    SCOPED_TRACE(name);
    try {
      write_shape(shape, path(name), format_from_path(name));
      FAIL() << "no exception";
    } catch (const WriteError& e) {
      EXPECT_EQ(e.file(), path(name));
    }
  }
  EXPECT_TRUE(listing().empty());
}

TEST_F(Exchange, FailedWriteKeepsTheOldFile) {
  std::ofstream(path("keep.step")) << "old content\n";
  EXPECT_THROW(write_shape(TopoDS_Shape(), path("keep.step"), Format::Step), ExportError);
  EXPECT_EQ(slurp(path("keep.step")), "old content\n");
  EXPECT_EQ(listing(), std::set<std::string>{"keep.step"});
}

TEST_F(Exchange, ReadShapeNamesTheFileOnFailure) {
  EXPECT_THROW(read_shape(path("absent.step")), InputError);
  std::ofstream(path("garbage.step")) << "this is not STEP\n";
  try {
    read_shape(path("garbage.step"));
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path("garbage.step"));
  }
  std::ofstream(path("garbage.brep")) << "neither is this\n";
  EXPECT_THROW(read_shape(path("garbage.brep")), InputError);
  EXPECT_THROW(read_shape(path("x.obj")), std::invalid_argument);
}

// The CLI prints --json on stdout; OCCT's translators print their statistics there unless
// silenced.
TEST_F(Exchange, ExchangeKeepsStdoutClean) {
  const TopoDS_Shape shape = build_brep(testing::unit_cube()).shape;
  ::testing::internal::CaptureStdout();
  write_shape(shape, path("q.step"), Format::Step);
  write_shape(shape, path("q.igs"), Format::Iges);
  read_shape(path("q.step"));
  read_shape(path("q.igs"));
  EXPECT_EQ(::testing::internal::GetCapturedStdout(), "");
}

}  // namespace
}  // namespace subd2nurbs::occt
