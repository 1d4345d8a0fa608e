#include <iostream>

#include "converter/cli/commands.h"
#include "io/atomic_file.h"

int main(int argc, char** argv) {
  // A run stopped by SIGINT / SIGTERM / SIGHUP removes its temporary output files.
  subd2nurbs::install_signal_cleanup();
  return subd2nurbs::cli::run(argc, argv, std::cout, std::cerr);
}
