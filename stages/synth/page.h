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
// Throws std::runtime_error when no font can be loaded.
Page MakePage(PageKind kind, cv::Size2d size_m, double dpi, std::mt19937* rng);

}  // namespace docunfold::synth
