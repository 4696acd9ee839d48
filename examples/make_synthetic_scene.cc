// Writes the synthetic scene's photos and true cameras into a folder: the input of the README's demo.
// Usage: make_synthetic_scene OUT_FOLDER [NUM_VIEWS [WIDTH HEIGHT [orbit|handheld|survey]]]

#include <cstdlib>
#include <exception>
#include <iostream>

#include "examples/synthetic_scene.h"

int main(int argc, char** argv) {
  if (argc < 2 || argc > 6 || argc == 4) {
    std::cerr << "usage: make_synthetic_scene OUT_FOLDER [NUM_VIEWS [WIDTH HEIGHT [orbit|handheld|survey]]]\n";
    return 1;
  }
  p2n::SyntheticSceneOptions options;
  if (argc >= 3) options.num_views = std::atoi(argv[2]);
  if (argc >= 5) {
    options.width = std::atoi(argv[3]);
    options.height = std::atoi(argv[4]);
  }
  if (argc == 6) options.path = argv[5];
  if (options.num_views < 1 || options.width < 16 || options.height < 16) {
    std::cerr << "make_synthetic_scene: NUM_VIEWS must be at least 1, WIDTH and HEIGHT at least 16\n";
    return 1;
  }
  try {
    p2n::WriteSyntheticScene(options, argv[1]);
  } catch (const std::exception& e) {
    std::cerr << "make_synthetic_scene: " << e.what() << "\n";
    return 1;
  }
  std::cout << "wrote " << options.num_views << " views of " << options.width << "x" << options.height << " to "
            << argv[1] << "\n";
  return 0;
}
