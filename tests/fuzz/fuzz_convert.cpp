// libFuzzer target: read -> validate -> patches at level 0 -> continuity (core only, no OCCT):
// an OBJ cage from the fuzzer's bytes through parse_obj, validate_cage, build_patches and
// measure_continuity. Small work only: cages up to 16 faces (128 face indices), and the
// resource guard's estimate (converter/pipeline), which decides what a real run refuses, here
// at 5 000 refined faces. With 64 faces and 2e4 refined faces each input cost about 5 ms and
// the fuzzer ran 200 inputs per second; the topologies the builder tells apart fit in 16 faces.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>

#include "converter/pipeline/resources.h"
#include "core/eval/continuity.h"
#include "core/patch/patch_builder.h"
#include "io/input_error.h"
#include "io/obj_reader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const subd2nurbs::LoadedCage cage = subd2nurbs::parse_obj(text, "fuzz.obj");
    if (cage.input.num_faces() > 16 || cage.input.face_indices.size() > 128) return 0;
    const subd2nurbs::SubdivLevel level =
        subd2nurbs::SubdivLevel::from_validated(subd2nurbs::validate_cage(cage), cage.input);
    // The pipeline's resource estimate (converter/pipeline/resources.h) at a fuzzing scale.
    if (subd2nurbs::pipeline::estimate_conversion(level, 0, false).faces > 5000) return 0;
    const std::vector<subd2nurbs::Point3> positions(cage.input.positions.begin(), cage.input.positions.end());
    bool surface = false;
    for (char hole : level.face_hole) surface = surface || !hole;
    if (!surface) return 0;  // the pipeline refuses all-hole cages before building patches
    subd2nurbs::PatchOptions options;
    const subd2nurbs::PatchBuild build = subd2nurbs::build_patches(level, positions, options);
    subd2nurbs::measure_continuity(build.set, 4);
  } catch (const subd2nurbs::InputError&) {
  } catch (const std::invalid_argument&) {
    // The patch builder's documented refusal of topology it does not support.
  }
  return 0;
}
