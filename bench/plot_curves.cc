// Plots held-out PSNR against training time from metrics.csv files (the train stage's), one line each.
// Usage: plot_curves OUT.png NAME=metrics.csv [NAME=metrics.csv ...]

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>

#include "nerf/plot.h"

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: plot_curves OUT.png NAME=metrics.csv ...\n");
    return 1;
  }
  std::vector<p2n::PlotSeries> series;
  for (int i = 2; i < argc; ++i) {
    const std::string argument = argv[i];
    const size_t equals = argument.find('=');
    p2n::PlotSeries line{argument.substr(0, equals), {}, {}};
    std::ifstream in(argument.substr(equals + 1));
    std::string row;
    std::getline(in, row);  // header: wall_seconds,step,train_loss,heldout_psnr
    while (std::getline(in, row)) {
      double seconds = 0, loss = 0, psnr = 0;
      int step = 0;
      if (std::sscanf(row.c_str(), "%lf,%d,%lf,%lf", &seconds, &step, &loss, &psnr) == 4 && std::isfinite(psnr)) {
        line.x.push_back(seconds);
        line.y.push_back(psnr);
      }
    }
    series.push_back(line);
  }
  p2n::WriteLinePlot(argv[1], {"held-out PSNR against training time", "training time (s)", "PSNR (dB)"}, series);
  return 0;
}
