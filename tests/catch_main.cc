#define CATCH_CONFIG_RUNNER
#include <catch2/catch.hpp>

#include "nerf/heap.h"

// The tests train and render as the program does: with freed blocks kept in the heap (nerf/heap.h).
int main(int argc, char* argv[]) {
  p2n::KeepFreedBlocksInHeap();
  return Catch::Session().run(argc, argv);
}
