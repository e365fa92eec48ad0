// Conversions between RGB24 and every other pixel format, for the simulator (which renders RGB
// and delivers what a real camera would), for pictures (PNG writes RGB) and for tests. Not the
// rectifier's path: it resamples every format natively (image_planes.hpp).
//
// YUV is BT.601 at full range (JFIF): Y = 0.299 R + 0.587 G + 0.114 B, U and V centred on 128.
// Chroma is averaged over the luma pixels it stands for, at its siting (pixel_format.hpp):
// 4:2:0 over its 2x2 cell, 4:2:2 with weights 1/4, 1/2, 1/4 around its even pixel. A mosaic
// keeps each site's colour; 16-bit samples are the 8-bit value times 257.
#pragma once

#include "dsp/core/image.hpp"

namespace rsd::dsp {

// rgb: an Rgb8 view; dst: any format, the same size (a size the format can hold).
void convert_from_rgb(const ImageView& rgb, const ImageView& dst);
// src: any format; rgb: an Rgb8 view of the same size. Chroma is replicated over the pixels
// it stands for; a mosaic is demosaiced bilinearly (each missing colour the mean of its
// nearest sites).
void convert_to_rgb(const ImageView& src, const ImageView& rgb);

// The luma of any format into a Mono8 view of the same size, for feature tracking (the online
// calibration's): Y itself for YUV (no chroma read), the high byte of 16-bit samples, BT.601
// integer luma for RGB, and for a mosaic (R + 2 G + B) / 4 of the 2x2 cell holding the pixel (a
// half-resolution picture without the sites' checkerboard). No allocation.
void convert_to_luma(const ImageView& src, const ImageView& mono8);

// The colour (0 R, 1 G, 2 B) of mosaic site (x, y) in a Bayer format.
int bayer_colour(PixelFormat f, int x, int y);

}  // namespace rsd::dsp
