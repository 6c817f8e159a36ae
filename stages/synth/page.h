// The printed page: its content drawn with real fonts, its text, and its
// true straight lines (text baselines, table rules, page edges).
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

namespace docunfold::synth {

enum class PageKind { kText, kTable, kReceipt, kPoster };

std::string PageKindName(PageKind kind);

struct PageLine {
  std::string kind;                     // text, rule or border
  std::vector<Eigen::Vector2d> points;  // page metres, u right, v down
};

struct Page {
  double width_m = 0.21, height_m = 0.297;
  cv::Mat image;  // 8-bit BGR, `pixels_per_m` resolution
  double pixels_per_m = 0;
  std::vector<std::string> text;  // one entry per text line, reading order
  std::vector<PageLine> lines;
};

// Default physical size of a kind (A4 for text, table and poster; a till
// roll for receipts), metres.
cv::Size2d DefaultPageSize(PageKind kind);

// Draws a page of the given kind at `dpi` (content chosen by the generator).
// A receipt with `roll_mm` 58 or 80 is laid out as a till prints on a roll of
// that width (RollColumns characters a line); 0 keeps the older, plainer
// receipt. Throws std::runtime_error when no font can be loaded.
Page MakePage(PageKind kind, cv::Size2d size_m, double dpi, std::mt19937* rng, int roll_mm = 0);

// Characters a line that a till prints on a roll `roll_mm` wide (the common
// 203-dpi printers' 12-dot font: 32 on 58 mm paper, 48 on 80 mm), and the
// printable width in metres.
int RollColumns(int roll_mm);
double RollPrintableWidth(int roll_mm);

}  // namespace docunfold::synth
