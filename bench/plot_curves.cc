// Plots held-out PSNR against training time from metrics.csv files (the train stage's), one line each.
// Usage: plot_curves OUT.png NAME=metrics.csv [NAME=metrics.csv ...]

#include <cstdio>
#include <fstream>
#include <iterator>
#include <string>

#include "base/plot.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: plot_curves OUT.png NAME=metrics.csv ...\n");
    return 1;
  }
  std::vector<p2n::PlotSeries> series;
  for (int i = 2; i < argc; ++i) {
    const std::string argument = argv[i];
    const size_t equals = argument.find('=');
    std::ifstream in(argument.substr(equals + 1));
    const std::string csv((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    series.push_back(p2n::CsvSeries(argument.substr(0, equals), csv, 0, 3));  // wall_seconds, heldout_psnr
  }
  p2n::WriteLinePlot(argv[1], {"held-out PSNR against training time", "training time (s)", "PSNR (dB)"}, series);
  return 0;
}
