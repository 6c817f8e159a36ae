#include "stages/synth/page.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <opencv2/freetype.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "stages/synth/random.h"

namespace docunfold::synth {
namespace {

namespace fs = std::filesystem;

constexpr double kMetresPerPoint = 0.0254 / 72;

// Font families by style, in order of preference; the Debian packages
// fonts-dejavu, fonts-liberation2 and fonts-freefont-ttf provide them.
const std::map<std::string, std::vector<std::string>> kFonts = {
    {"serif",
     {"/usr/share/fonts/truetype/dejavu/DejaVuSerif.ttf",
      "/usr/share/fonts/truetype/liberation2/LiberationSerif-Regular.ttf",
      "/usr/share/fonts/truetype/freefont/FreeSerif.ttf"}},
    {"serif-bold",
     {"/usr/share/fonts/truetype/dejavu/DejaVuSerif-Bold.ttf",
      "/usr/share/fonts/truetype/liberation2/LiberationSerif-Bold.ttf",
      "/usr/share/fonts/truetype/freefont/FreeSerifBold.ttf"}},
    {"sans",
     {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
      "/usr/share/fonts/truetype/liberation2/LiberationSans-Regular.ttf",
      "/usr/share/fonts/truetype/freefont/FreeSans.ttf"}},
    {"sans-bold",
     {"/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf",
      "/usr/share/fonts/truetype/liberation2/LiberationSans-Bold.ttf",
      "/usr/share/fonts/truetype/freefont/FreeSansBold.ttf"}},
    {"mono",
     {"/usr/share/fonts/truetype/dejavu/DejaVuSansMono.ttf",
      "/usr/share/fonts/truetype/liberation2/LiberationMono-Regular.ttf",
      "/usr/share/fonts/truetype/freefont/FreeMono.ttf"}},
    {"mono-bold",
     {"/usr/share/fonts/truetype/dejavu/DejaVuSansMono-Bold.ttf",
      "/usr/share/fonts/truetype/liberation2/LiberationMono-Bold.ttf",
      "/usr/share/fonts/truetype/freefont/FreeMonoBold.ttf"}},
};

// Running text: paragraphs of the licence texts every Debian system has.
std::vector<std::string> Paragraphs(std::mt19937* rng) {
  const std::vector<std::string> files = {"GPL-3",    "Apache-2.0", "MPL-2.0",
                                          "GFDL-1.3", "LGPL-2.1",   "Artistic"};
  std::vector<std::string> available;
  for (const std::string& f : files)
    if (fs::exists("/usr/share/common-licenses/" + f)) available.push_back(f);
  std::vector<std::string> paragraphs;
  if (available.empty()) {
    paragraphs.push_back(
        "The quick brown fox jumps over the lazy dog while the five boxing wizards "
        "jump quickly and a wizard's job is to vex chumps quickly in fog.");
    return paragraphs;
  }
  std::ifstream in("/usr/share/common-licenses/" + available[(*rng)() % available.size()]);
  std::string line, current;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    std::string w, cleaned;
    while (words >> w) cleaned += (cleaned.empty() ? "" : " ") + w;
    if (cleaned.empty()) {
      if (current.size() > 80) paragraphs.push_back(current);
      current.clear();
    } else {
      current += (current.empty() ? "" : " ") + cleaned;
    }
  }
  if (current.size() > 80) paragraphs.push_back(current);
  if (paragraphs.empty()) paragraphs.push_back("No text.");
  std::rotate(paragraphs.begin(), paragraphs.begin() + (*rng)() % paragraphs.size(),
              paragraphs.end());
  return paragraphs;
}

template <typename T>
const T& Pick(const std::vector<T>& v, std::mt19937* rng) {
  return v[(*rng)() % v.size()];
}

std::string Money(double value) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2f", value);
  return buf;
}

// Draws text and rules on the page image in page metres and records what it
// drew as ground truth.
class Typesetter {
 public:
  Typesetter(Page* page, std::mt19937* rng) : page_(page), rng_(rng) {
    for (const auto& [style, files] : kFonts) {
      // One face per style for the whole page, chosen by the generator.
      std::vector<std::string> present;
      for (const std::string& f : files)
        if (fs::exists(f)) present.push_back(f);
      if (present.empty()) continue;
      auto ft = cv::freetype::createFreeType2();
      ft->loadFontData(Pick(present, rng_), 0);
      fonts_[style] = ft;
    }
    if (fonts_.empty())
      throw std::runtime_error(
          "no TrueType fonts found (install fonts-dejavu-core, fonts-liberation2 or "
          "fonts-freefont-ttf)");
  }

  int Px(double metres) const { return int(std::lround(metres * page_->pixels_per_m)); }

  cv::Ptr<cv::freetype::FreeType2> Font(const std::string& style) const {
    auto it = fonts_.find(style);
    if (it != fonts_.end()) return it->second;
    return fonts_.begin()->second;
  }

  // Advance width of `text` in metres.
  double Width(const std::string& style, double size_pt, const std::string& text) const {
    int baseline = 0;
    const int h = std::max(1, Px(size_pt * kMetresPerPoint));
    return Font(style)->getTextSize(text, h, -1, &baseline).width / page_->pixels_per_m;
  }

  // Draws `text` with its baseline starting at (u, v); records it as a text
  // line of the page (one line of text.txt unless `same_line`), and its
  // baseline as a true straight line.
  void Text(const std::string& style, double size_pt, const std::string& text, double u, double v,
            const cv::Scalar& colour, bool same_line = false) {
    if (text.find_first_not_of(' ') == std::string::npos) return;
    Ink(style, size_pt, text, u, v, colour);
    const double w = Width(style, size_pt, text);
    // The baseline runs under the inked characters, not the leading spaces.
    const size_t first = text.find_first_not_of(' ');
    const double u0 = u + (first ? Width(style, size_pt, text.substr(0, first)) : 0);
    page_->lines.push_back({"text", {{u0, v}, {u + w, v}}});
    if (same_line && !page_->text.empty())
      page_->text.back() += "  " + text.substr(first);
    else
      page_->text.push_back(text.substr(first));
  }

  // Draws a row of rule characters (a till's "-----", "=====" or "....."):
  // the row is a line of text.txt, but nothing of it sits on its baseline,
  // so each bar of its ink is recorded as a true rule line instead, along
  // the middle of the bar.
  void RuleRow(const std::string& style, double size_pt, const std::string& text, double u,
               double v, const cv::Scalar& colour) {
    Ink(style, size_pt, text, u, v, colour);
    page_->text.push_back(text);
    // The row drawn again alone, black on white, baseline at (h, h).
    const int h = std::max(1, Px(size_pt * kMetresPerPoint));
    const int w = Px(u + Width(style, size_pt, text)) - Px(u);
    cv::Mat scratch(2 * h, w + 2 * h, CV_8UC3, cv::Scalar(255, 255, 255));
    Font(style)->putText(scratch, text, cv::Point(h, h), h, cv::Scalar(0, 0, 0), -1, cv::LINE_AA,
                         true);
    cv::Mat1b dark;
    cv::cvtColor(scratch, dark, cv::COLOR_BGR2GRAY);
    dark = dark < 128;
    // Rows of ink across a tenth of the row or more (dots too) make a bar.
    std::vector<int> count(size_t(dark.rows));
    for (int y = 0; y < dark.rows; ++y) count[size_t(y)] = cv::countNonZero(dark.row(y));
    for (int y = 0; y < dark.rows;) {
      if (count[size_t(y)] < 0.1 * w) {
        ++y;
        continue;
      }
      double sum = 0, weight = 0;
      int x0 = dark.cols, x1 = -1;
      for (; y < dark.rows && count[size_t(y)] >= 0.1 * w; ++y) {
        sum += double(y) * count[size_t(y)];
        weight += count[size_t(y)];
        for (int x = 0; x < dark.cols; ++x)
          if (dark(y, x)) {
            x0 = std::min(x0, x);
            x1 = std::max(x1, x);
          }
      }
      const double bar_v = v + (sum / weight + 0.5 - h) / page_->pixels_per_m;  // row centres
      page_->lines.push_back({"rule",
                              {{u + (x0 - h) / page_->pixels_per_m, bar_v},
                               {u + (x1 + 1 - h) / page_->pixels_per_m, bar_v}}});
    }
  }

  // Draws `text` only (no ground truth).
  void Ink(const std::string& style, double size_pt, const std::string& text, double u, double v,
           const cv::Scalar& colour) {
    const int h = std::max(1, Px(size_pt * kMetresPerPoint));
    Font(style)->putText(page_->image, text, cv::Point(Px(u), Px(v)), h, colour, -1, cv::LINE_AA,
                         true);
  }

  void Rule(double u0, double v0, double u1, double v1, double thickness_m,
            const cv::Scalar& colour) {
    cv::line(page_->image, cv::Point(Px(u0), Px(v0)), cv::Point(Px(u1), Px(v1)), colour,
             std::max(1, Px(thickness_m)), cv::LINE_AA);
    page_->lines.push_back({"rule", {{u0, v0}, {u1, v1}}});
  }

  void Fill(double u0, double v0, double u1, double v1, const cv::Scalar& colour) {
    cv::rectangle(page_->image, cv::Point(Px(u0), Px(v0)), cv::Point(Px(u1), Px(v1)), colour,
                  cv::FILLED);
  }

  // Words of `paragraph` broken into lines no wider than `width`.
  std::vector<std::string> Wrap(const std::string& style, double size_pt,
                                const std::string& paragraph, double width) const {
    std::vector<std::string> lines;
    std::istringstream words(paragraph);
    std::string word, line;
    while (words >> word) {
      const std::string candidate = line.empty() ? word : line + " " + word;
      if (!line.empty() && Width(style, size_pt, candidate) > width) {
        lines.push_back(line);
        line = word;
      } else {
        line = candidate;
      }
    }
    if (!line.empty()) lines.push_back(line);
    return lines;
  }

  std::mt19937* rng() const { return rng_; }

 private:
  Page* page_;
  std::mt19937* rng_;
  std::map<std::string, cv::Ptr<cv::freetype::FreeType2>> fonts_;
};

cv::Scalar Ink(std::mt19937* rng) {
  const double k = Uniform(rng, 15, 45);
  return {k + Uniform(rng, 0, 10), k, k};
}

void DrawTextPage(Typesetter& ts, Page& page, std::mt19937* rng) {
  const double margin = Uniform(rng, 0.018, 0.026);
  const double size = Uniform(rng, 9.5, 11.5);
  const double leading = size * kMetresPerPoint * Uniform(rng, 1.3, 1.45);
  const cv::Scalar ink = Ink(rng);
  const double right = page.width_m - margin;
  double v = margin + 0.012;
  auto paragraphs = Paragraphs(rng);
  const std::string title = "Terms and Conditions " + std::to_string(100 + (*rng)() % 800);
  ts.Text("serif-bold", size * 1.5, title, margin, v, ink);
  v += leading * 2;
  for (const std::string& p : paragraphs) {
    for (const std::string& line : ts.Wrap("serif", size, p, right - margin)) {
      if (v > page.height_m - margin - 0.01) break;
      ts.Text("serif", size, line, margin, v, ink);
      v += leading;
    }
    v += leading * 0.6;
    if (v > page.height_m - margin - 0.01) break;
  }
  const std::string number = "- " + std::to_string(1 + (*rng)() % 40) + " -";
  ts.Text("serif", size * 0.9, number, page.width_m / 2 - ts.Width("serif", size * 0.9, number) / 2,
          page.height_m - margin * 0.55, ink);
}

void DrawTablePage(Typesetter& ts, Page& page, std::mt19937* rng) {
  const double margin = Uniform(rng, 0.016, 0.022);
  const double size = Uniform(rng, 8.5, 10);
  const double line_h = size * kMetresPerPoint * 1.45;
  const cv::Scalar ink = Ink(rng);
  const double right = page.width_m - margin;
  double v = margin + 0.012;
  ts.Text("sans-bold", size * 1.8, "ACCOUNT STATEMENT", margin, v, ink);
  v += line_h * 2;
  const std::vector<std::string> names = {"Alex Morgan", "Sam Taylor",   "Jordan Lee",
                                          "Casey Brown", "Robin Clarke", "Maria Rossi"};
  const std::vector<std::string> streets = {"Mill Lane",   "Harbour Road", "Station Street",
                                            "Church Walk", "Kings Avenue", "Elm Grove"};
  ts.Text("sans", size, Pick(names, rng), margin, v, ink);
  v += line_h;
  ts.Text("sans", size, std::to_string(3 + (*rng)() % 90) + " " + Pick(streets, rng), margin, v,
          ink);
  v += line_h;
  ts.Text("sans", size,
          "Account " + std::to_string(10000000 + (*rng)() % 89999999) + "   Sort code 20-" +
              std::to_string(10 + (*rng)() % 89) + "-" + std::to_string(10 + (*rng)() % 89),
          margin, v, ink);
  v += line_h * 1.8;

  // The table: columns, rules, a shaded header.
  const std::vector<std::string> headers = {"Date", "Description", "Paid out", "Paid in",
                                            "Balance"};
  const std::vector<double> fractions = {0.13, 0.42, 0.15, 0.15, 0.15};
  std::vector<double> col_u = {margin};
  for (double f : fractions) col_u.push_back(col_u.back() + f * (right - margin));
  const double row_h = Uniform(rng, 0.0062, 0.0078);
  const bool vertical_rules = (*rng)() % 2 == 0;
  const bool every_row_ruled = (*rng)() % 3 != 0;
  const double thin = Uniform(rng, 0.00018, 0.0003), thick = thin * 2.2;
  const cv::Scalar rule_colour = ink;
  const double top = v;
  ts.Fill(margin, top, right, top + row_h, cv::Scalar(222, 222, 222));
  for (size_t c = 0; c < headers.size(); ++c)
    ts.Text("sans-bold", size, headers[c], col_u[c] + 0.0015, top + row_h * 0.72, ink, c > 0);
  const std::vector<std::string> what = {"Card payment", "Direct debit",   "Transfer to",
                                         "Cash machine", "Standing order", "Interest",
                                         "Salary",       "Refund from"};
  const std::vector<std::string> who = {"GROCER",   "RAILWAYS", "ENERGY CO",   "BOOKSHOP",
                                        "PHARMACY", "CAFE",     "COUNCIL TAX", "GARAGE"};
  const int rows = int(std::floor((page.height_m - margin - 0.05 - (top + row_h)) / row_h));
  double balance = Uniform(rng, 200, 3000);
  int day = 1 + (*rng)() % 5;
  double row_v = top + row_h;
  for (int r = 0; r < std::max(rows, 3); ++r) {
    const bool paid_in = (*rng)() % 5 == 0;
    const double amount = paid_in ? Uniform(rng, 100, 1500) : Uniform(rng, 2, 180);
    balance += paid_in ? amount : -amount;
    day = std::min(28, day + int((*rng)() % 3));
    const std::vector<std::string> cells = {
        std::to_string(day) + " Mar", Pick(what, rng) + " " + Pick(who, rng),
        paid_in ? "" : Money(amount), paid_in ? Money(amount) : "", Money(balance)};
    const double baseline = row_v + row_h * 0.72;
    bool first = true;
    for (size_t c = 0; c < cells.size(); ++c) {
      if (cells[c].empty()) continue;
      double u = col_u[c] + 0.0015;
      if (c >= 2) u = col_u[c + 1] - 0.0015 - ts.Width("sans", size, cells[c]);
      ts.Text("sans", size, cells[c], u, baseline, ink, !first);
      first = false;
    }
    row_v += row_h;
    if (every_row_ruled && r + 1 < rows) ts.Rule(margin, row_v, right, row_v, thin, rule_colour);
  }
  ts.Rule(margin, top, right, top, thick, rule_colour);
  ts.Rule(margin, top + row_h, right, top + row_h, thin, rule_colour);
  ts.Rule(margin, row_v, right, row_v, thick, rule_colour);
  if (vertical_rules)
    for (double u : col_u) ts.Rule(u, top, u, row_v, thin, rule_colour);
  v = row_v + line_h * 1.6;
  auto paragraphs = Paragraphs(rng);
  for (const std::string& line : ts.Wrap("sans", size * 0.85, paragraphs[0], right - margin)) {
    if (v > page.height_m - margin) break;
    ts.Text("sans", size * 0.85, line, margin, v, ink);
    v += line_h * 0.9;
  }
}

void DrawReceipt(Typesetter& ts, Page& page, std::mt19937* rng) {
  const double margin = Uniform(rng, 0.005, 0.008);
  const double size = Uniform(rng, 8, 9.5);
  const double line_h = size * kMetresPerPoint * 1.5;
  const cv::Scalar ink = Ink(rng);
  const double right = page.width_m - margin;
  // Advance of one character (a single glyph's box is narrower).
  const double char_w = ts.Width("mono", size, std::string(20, '0')) / 20;
  const int columns = int((right - margin) / char_w);
  double v = margin + 0.01;
  const std::vector<std::string> shops = {"CORNER MARKET", "GREEN GROCER", "CITY PHARMACY",
                                          "BOOK NOOK", "HARDWARE HUT"};
  const std::string shop = Pick(shops, rng);
  ts.Text("mono-bold", size * 1.3, shop,
          (page.width_m - ts.Width("mono-bold", size * 1.3, shop)) / 2, v, ink);
  v += line_h * 1.4;
  ts.Text(
      "mono", size,
      "Store " + std::to_string(1 + (*rng)() % 99) + "  Till " + std::to_string(1 + (*rng)() % 9),
      margin, v, ink);
  v += line_h;
  ts.Text("mono", size, std::string(columns, '-'), margin, v, ink);
  v += line_h;
  const std::vector<std::string> items = {"Bread", "Milk 1L",  "Apples",   "Cheese", "Coffee",
                                          "Pasta", "Tomatoes", "Rice 2kg", "Butter", "Soap",
                                          "Tea",   "Eggs x6",  "Onions",   "Yoghurt"};
  double total = 0;
  while (v < page.height_m - margin - line_h * 5) {
    const std::string item = Pick(items, rng);
    const std::string price = Money(Uniform(rng, 0.5, 15));
    total += std::stod(price);
    std::string row = item;
    row += std::string(std::max(1, columns - int(item.size()) - int(price.size())), ' ');
    row += price;
    ts.Text("mono", size, row, margin, v, ink);
    v += line_h;
  }
  ts.Text("mono", size, std::string(columns, '-'), margin, v, ink);
  v += line_h;
  const std::string amount = Money(total);
  ts.Text("mono-bold", size,
          "TOTAL" + std::string(std::max(1, columns - 5 - int(amount.size())), ' ') + amount,
          margin, v, ink);
  v += line_h * 1.5;
  ts.Text("mono", size, "THANK YOU", (page.width_m - ts.Width("mono", size, "THANK YOU")) / 2, v,
          ink);
}

// Prints monospaced rows down a till roll: every row `columns` characters
// from `left`, so that spaces right-align prices as a till does.
struct RollPrinter {
  Typesetter& ts;
  cv::Scalar ink;
  double left, size, line_h;
  int columns;
  double v;

  // A row in characters `columns / cols` times as large as the body's
  // (cols: the row's width in those characters); bold is struck twice a
  // dot apart, as a thermal till's emphasis is, in the same face.
  void Row(const std::string& text, bool bold = false, int cols = 0) {
    const double scale = cols > 0 ? double(columns) / cols : 1;
    v += line_h * (scale - 1);
    if (bold) ts.Ink("mono", size * scale, text, left + 0.000125, v, ink);
    ts.Text("mono", size * scale, text, left, v, ink);
    v += line_h;
  }
  void Centre(const std::string& text, bool bold = false, int cols = 0) {
    const int width = cols > 0 ? cols : columns;
    Row(std::string(std::max(0, (width - int(text.size())) / 2), ' ') + text, bold, cols);
  }
  // `name` at the left, `amount` ending in the last column.
  void Item(const std::string& name, const std::string& amount, bool bold = false, int cols = 0) {
    const int width = cols > 0 ? cols : columns;
    const std::string shown = name.substr(0, std::max(1, width - int(amount.size()) - 1));
    Row(shown + std::string(std::max(1, width - int(shown.size()) - int(amount.size())), ' ') +
            amount,
        bold, cols);
  }
  void Rule(char c) {
    ts.RuleRow("mono", size, std::string(columns, c), left, v, ink);
    v += line_h;
  }
};

struct RollItem {
  std::string name;
  double unit;  // price of one, or of a kilogram
  bool by_weight;
};

// A receipt as a till prints it on a 58 or 80 mm roll: a centred header
// (shop, address, telephone, VAT number), the store, till and date, a dashed,
// dotted or double separator, the items (name left, a gap, the price in the
// last column; a quantity or weight row under some), subtotal, a larger
// TOTAL, the payment, a VAT summary and a centred footer.
void DrawRollReceipt(Typesetter& ts, Page& page, int roll_mm, std::mt19937* rng) {
  const int columns = RollColumns(roll_mm);
  const double printable = std::min(RollPrintableWidth(roll_mm), page.width_m - 0.004);
  // The font size that puts `columns` advances across the printable width.
  const double advance_per_pt = ts.Width("mono", 10, std::string(20, '0')) / 20 / 10;
  const double size = printable / columns / advance_per_pt;
  const double line_h = size * kMetresPerPoint * Uniform(rng, 1.45, 1.7);
  RollPrinter p{ts,     Ink(rng), (page.width_m - printable) / 2, size,
                line_h, columns,  Uniform(rng, 0.006, 0.012)};
  const char rule = std::string("-.=")[(*rng)() % 3];
  const std::vector<std::string> shops = {"CORNER MARKET", "GREEN GROCER", "CITY PHARMACY",
                                          "BOOK NOOK",     "HARDWARE HUT", "FRESH FOODS"};
  const std::vector<std::string> streets = {"Mill Lane",   "Harbour Road",  "Station Street",
                                            "Church Walk", "Market Square", "Elm Grove"};
  // Header: the shop's name larger, then its address and numbers.
  const std::string shop = Pick(shops, rng);
  // Larger rows: three quarters as many characters, each a third larger.
  const int big = columns * 3 / 4;
  p.Centre(shop, true, big);
  p.Centre(std::to_string(1 + (*rng)() % 180) + " " + Pick(streets, rng));
  p.Centre("Tel 01632 " + std::to_string(100000 + (*rng)() % 900000));
  p.Centre("VAT No GB " + std::to_string(100 + (*rng)() % 900) + " " +
           std::to_string(1000 + (*rng)() % 9000) + " " + std::to_string(10 + (*rng)() % 90));
  p.v += line_h * 0.5;
  char when[64];
  std::snprintf(when, sizeof when, "%02d/%02d/2026 %02d:%02d", 1 + int((*rng)() % 28),
                1 + int((*rng)() % 12), 8 + int((*rng)() % 12), int((*rng)() % 60));
  p.Item(
      "Store " + std::to_string(1 + (*rng)() % 99) + "  Till " + std::to_string(1 + (*rng)() % 9),
      "Op " + std::to_string(100 + (*rng)() % 900));
  p.Item(when, "No " + std::to_string(1000 + (*rng)() % 9000));
  p.Rule(rule);

  // Items down to the room the totals and footer need.
  const std::vector<std::string> items = {
      "Bread",  "Milk 1L", "Cheddar 400g", "Coffee beans", "Pasta",      "Rice 2kg",
      "Butter", "Soap",    "Tea bags 80",  "Eggs x6",      "Yoghurt",    "Orange juice",
      "Cereal", "Tuna",    "Olive oil",    "Biscuits",     "Washing up", "Toothpaste"};
  const std::vector<std::string> weighed = {"Apples", "Bananas", "Tomatoes",
                                            "Onions", "Carrots", "Grapes"};
  const bool vat_codes = (*rng)() % 2 == 0;
  const double footer_lines = 12.5;
  const double bottom = page.height_m - Uniform(rng, 0.008, 0.015) - footer_lines * line_h;
  double total = 0, taxed = 0;
  int count = 0;
  while (p.v + line_h < bottom || count < 3) {
    const int kind = int((*rng)() % 6);  // 0 weighed, 1 several, else one
    RollItem item{kind == 0 ? Pick(weighed, rng) : Pick(items, rng), Uniform(rng, 0.4, 9.5),
                  kind == 0};
    const int quantity = kind == 1 ? 2 + int((*rng)() % 4) : 1;
    const double weight = Uniform(rng, 0.2, 1.6);
    const double price =
        std::round((item.by_weight ? item.unit * weight : item.unit * quantity) * 100) / 100;
    if ((kind <= 1) && p.v + 2 * line_h >= bottom && count >= 3) break;
    // Food at 0 % VAT (B), household goods at 20 % (A).
    const bool vat_a =
        item.name == "Soap" || item.name == "Toothpaste" || item.name == "Washing up";
    if (vat_a) taxed += price;
    p.Item(item.name, Money(price) + (vat_codes ? (vat_a ? " A" : " B") : ""));
    if (item.by_weight) {
      char row[64];
      std::snprintf(row, sizeof row, "  %.3f kg @ %s/kg", weight, Money(item.unit).c_str());
      p.Row(row);
    } else if (quantity > 1) {
      p.Row("  " + std::to_string(quantity) + " @ " + Money(item.unit));
    }
    total += price;
    ++count;
  }

  // Totals, payment, VAT and the footer.
  p.Rule(rule);
  p.Item(std::to_string(count) + " ITEMS  SUBTOTAL", Money(total));
  p.Item("TOTAL", Money(total), true, big);
  p.v += line_h * 0.3;
  if ((*rng)() % 2 == 0) {
    p.Item("CARD  ************" + std::to_string(1000 + (*rng)() % 9000), Money(total));
    p.Item("AUTH CODE", std::to_string(100000 + (*rng)() % 900000));
  } else {
    const double cash = std::ceil(total / 10 + 0.01) * 10;
    p.Item("CASH", Money(cash));
    p.Item("CHANGE", Money(cash - total));
  }
  p.Rule(rule);
  p.Item("VAT  A 20%", Money(taxed * 0.2 / 1.2));
  p.Item("VAT  B  0%", Money(0));
  p.v += line_h * 0.5;
  p.Centre("THANK YOU FOR SHOPPING");
  p.Centre("PLEASE KEEP YOUR RECEIPT");
  p.Centre("Returns within 28 days");
}

void DrawPoster(Typesetter& ts, Page& page, std::mt19937* rng) {
  const double margin = Uniform(rng, 0.015, 0.022);
  const cv::Scalar ink = Ink(rng);
  const double right = page.width_m - margin;
  const cv::Scalar band(Uniform(rng, 150, 235), Uniform(rng, 150, 235), Uniform(rng, 150, 235));
  const double band_h = Uniform(rng, 0.045, 0.06);
  ts.Fill(0, 0, page.width_m, band_h, band);
  const std::vector<std::string> titles = {"OPEN DAY", "SUMMER FAIR", "CITY MARATHON",
                                           "BOOK FESTIVAL", "SCIENCE WEEK"};
  const std::string title = Pick(titles, rng) + " " + std::to_string(2025 + (*rng)() % 4);
  const double title_size = Uniform(rng, 26, 34);
  ts.Text("sans-bold", title_size, title, margin, band_h * 0.68, ink);
  double v = band_h + 0.016;
  ts.Text("sans", 14, "Programme", margin, v, ink);
  v += 0.01;
  auto paragraphs = Paragraphs(rng);
  const int boxes = 2 + (*rng)() % 3;
  const double gap = 0.008;
  const double box_h = (page.height_m - margin - 0.02 - v - gap * boxes) / boxes;
  const double size = Uniform(rng, 9.5, 11);
  const double line_h = size * kMetresPerPoint * 1.4;
  const double thickness = Uniform(rng, 0.0005, 0.0009);
  for (int b = 0; b < boxes; ++b) {
    const double top = v + gap + b * (box_h + gap), bottom = top + box_h;
    ts.Rule(margin, top, right, top, thickness, ink);
    ts.Rule(right, top, right, bottom, thickness, ink);
    ts.Rule(right, bottom, margin, bottom, thickness, ink);
    ts.Rule(margin, bottom, margin, top, thickness, ink);
    double tv = top + 0.011;
    ts.Text("sans-bold", size * 1.25,
            std::to_string(9 + b * 2) + ":00  Session " + std::to_string(b + 1), margin + 0.006, tv,
            ink);
    tv += line_h * 1.5;
    for (const std::string& line :
         ts.Wrap("sans", size, paragraphs[b % paragraphs.size()], right - margin - 0.012)) {
      if (tv > bottom - 0.006) break;
      ts.Text("sans", size, line, margin + 0.006, tv, ink);
      tv += line_h;
    }
  }
  ts.Text("sans", 9, "Admission free. All welcome.", margin, page.height_m - margin * 0.7, ink);
}

}  // namespace

std::string PageKindName(PageKind kind) {
  switch (kind) {
    case PageKind::kText:
      return "text";
    case PageKind::kTable:
      return "table";
    case PageKind::kReceipt:
      return "receipt";
    case PageKind::kPoster:
      return "poster";
  }
  return "text";
}

cv::Size2d DefaultPageSize(PageKind kind) {
  return kind == PageKind::kReceipt ? cv::Size2d(0.08, 0.2) : cv::Size2d(0.21, 0.297);
}

int RollColumns(int roll_mm) { return roll_mm >= 80 ? 48 : 32; }

double RollPrintableWidth(int roll_mm) { return roll_mm >= 80 ? 0.072 : 0.048; }

Page MakePage(PageKind kind, cv::Size2d size_m, double dpi, std::mt19937* rng, int roll_mm) {
  Page page;
  page.width_m = size_m.width;
  page.height_m = size_m.height;
  page.pixels_per_m = dpi / 0.0254;
  const double paper = Uniform(rng, 238, 252);
  page.image = cv::Mat(int(std::lround(page.height_m * page.pixels_per_m)),
                       int(std::lround(page.width_m * page.pixels_per_m)), CV_8UC3,
                       cv::Scalar(paper - Uniform(rng, 0, 8), paper - Uniform(rng, 0, 3), paper));
  Typesetter ts(&page, rng);
  switch (kind) {
    case PageKind::kText:
      DrawTextPage(ts, page, rng);
      break;
    case PageKind::kTable:
      DrawTablePage(ts, page, rng);
      break;
    case PageKind::kReceipt:
      if (roll_mm > 0)
        DrawRollReceipt(ts, page, roll_mm, rng);
      else
        DrawReceipt(ts, page, rng);
      break;
    case PageKind::kPoster:
      DrawPoster(ts, page, rng);
      break;
  }
  const double W = page.width_m, H = page.height_m;
  page.lines.push_back({"border", {{0, 0}, {W, 0}}});
  page.lines.push_back({"border", {{W, 0}, {W, H}}});
  page.lines.push_back({"border", {{W, H}, {0, H}}});
  page.lines.push_back({"border", {{0, H}, {0, 0}}});
  return page;
}

}  // namespace docunfold::synth
