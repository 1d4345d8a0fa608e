// Writes sample_patch_set() as JSON to argv[1] (input of check_patch_json.py).
#include <cstdio>
#include <exception>

#include "io/patch_json.h"
#include "io/sample_patch_set.h"

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT.json\n", argv[0]);
    return 2;
  }
  try {
    subd2nurbs::write_patch_json(argv[1], subd2nurbs::testing::sample_patch_set());
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
