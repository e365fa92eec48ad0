// A PLplot page for the tools' figures: the device from the file name (.svg: SVG, otherwise
// PNG), the size in pixels (points for SVG, so both have the same layout), a palette of cmap0
// colours, PLplot's sans-serif font at its default height.
#pragma once

#include <initializer_list>
#include <string>

namespace rsd::tools {

struct PlotColour {
  int index;  // cmap0 index the figure draws with (0 is the background)
  int r, g, b;
};

// Opens the page and advances to it; the caller draws, then plend() writes the file.
void open_plot_page(const std::string& file, int width, int height, std::initializer_list<PlotColour> palette);

}  // namespace rsd::tools
