// Text for HTML and XML: the five characters with a meaning in markup
// replaced by their entities.
#pragma once

#include <string>

namespace docunfold {

// `text` with & < > " ' as &amp; &lt; &gt; &quot; &#39; (the escaping
// Tesseract applies to what it writes into ALTO and hOCR; valid in HTML text
// and attribute values alike).
std::string MarkupEscape(const std::string& text);

}  // namespace docunfold
