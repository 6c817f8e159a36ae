// Tesseract's ALTO and hOCR give positions in the pixels of the image it
// read; the page is read enlarged, and these map them onto the page's own.
#pragma once

#include <string>

namespace docunfold::pdf {

// Every HPOS, VPOS, WIDTH and HEIGHT attribute times `scale`, rounded.
std::string ScaleAltoPixels(const std::string& alto, double scale);

// Every bbox, baseline offset, x_size, x_descenders and x_ascenders times
// `scale`, and scan_res set to `page_dpi` (the resolution Tesseract was
// told, `read_dpi`, is that of the enlarged copy).
std::string ScaleHocrPixels(const std::string& hocr, double scale, int read_dpi, int page_dpi);

}  // namespace docunfold::pdf
