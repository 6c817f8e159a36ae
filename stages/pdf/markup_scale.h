// Tesseract's ALTO and hOCR edited after it wrote them: positions are in the
// pixels of the image it read, and the page is read enlarged, so these map
// them onto the page's own; words read again are replaced in them.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "stages/pdf/text_size.h"

namespace docunfold::pdf {

// Every HPOS, VPOS, WIDTH and HEIGHT attribute times `scale`, rounded.
std::string ScaleAltoPixels(const std::string& alto, double scale);

// Every bbox, baseline offset, x_size, x_descenders and x_ascenders times
// `scale`, and scan_res set to `page_dpi` (the resolution Tesseract was
// told, `read_dpi`, is that of the enlarged copy).
std::string ScaleHocrPixels(const std::string& hocr, double scale, int read_dpi, int page_dpi);

// `alto` with each replaced word's String given its new CONTENT, WC and box,
// and a dropped word's String removed with the SP before it; nullopt when
// the file's words are not the replacements' old texts where they say.
std::optional<std::string> ReplaceAltoWords(const std::string& alto,
                                            const std::vector<WordReplacement>& replacements);

// The same for hOCR's ocrx_word spans (their text, bbox and x_wconf).
std::optional<std::string> ReplaceHocrWords(const std::string& hocr,
                                            const std::vector<WordReplacement>& replacements);

}  // namespace docunfold::pdf
