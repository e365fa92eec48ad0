#include "tools/report/plot_page.hpp"

#include <plplot.h>

namespace rsd::tools {

void open_plot_page(const std::string& file, int width, int height, std::initializer_list<PlotColour> palette) {
  plsdev(file.ends_with(".svg") ? "svgcairo" : "pngcairo");
  plsfnam(file.c_str());
  plspage(0, 0, width, height, 0, 0);
  for (const PlotColour& c : palette) plscol0(c.index, c.r, c.g, c.b);
  plinit();
  plfont(1);
  plschr(0, 1.0);
  pladv(0);
}

}  // namespace rsd::tools
