// The `catgraph` command. All logic is in the catgraph::apps library so the
// tests run the same code in process.
#include <iostream>

#include "apps/commands.h"

int main(int argc, char** argv) {
  return catgraph::RunCatgraph(argc, argv, std::cout, std::cerr);
}
