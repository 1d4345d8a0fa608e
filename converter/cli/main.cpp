#include <cstdlib>
#include <iostream>

#include "converter/cli/commands.h"
#include "io/atomic_file.h"

int main(int argc, char** argv) {
  // A run stopped by SIGINT / SIGTERM / SIGHUP removes its temporary output files.
  // SUBD2NURBS_TEST_NO_SIGNAL_CLEANUP: the signal test's control run, which must see the
  // temporary files left behind (the test can fail).
  if (!std::getenv("SUBD2NURBS_TEST_NO_SIGNAL_CLEANUP")) subd2nurbs::install_signal_cleanup();
  return subd2nurbs::cli::run(argc, argv, std::cout, std::cerr);
}
