#include <iostream>

#include "converter/cli/commands.h"

int main(int argc, char** argv) { return subd2nurbs::cli::run(argc, argv, std::cout, std::cerr); }
