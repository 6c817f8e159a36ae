#include "stages/detect-features/detect_features.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "common/errors.h"
#include "common/option_table.h"
#include "common/program.h"
#include "stages/detect-features/feature_parts.h"

namespace docunfold::features {
namespace detail {

cv::Mat1b SauvolaInk(const cv::Mat1b& grey, int window, double k) {
  cv::Mat1f g, mean, mean2;
  grey.convertTo(g, CV_32F);
  const cv::Size size(window, window);
  cv::boxFilter(g, mean, CV_32F, size, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::boxFilter(g.mul(g), mean2, CV_32F, size, cv::Point(-1, -1), true, cv::BORDER_REFLECT);
  cv::Mat1b ink(grey.size(), uchar(0));
  for (int y = 0; y < grey.rows; ++y) {
    const float* gp = g.ptr<float>(y);
    const float* mp = mean.ptr<float>(y);
    const float* m2 = mean2.ptr<float>(y);
    uchar* out = ink.ptr<uchar>(y);
    for (int x = 0; x < grey.cols; ++x) {
      const float sd = std::sqrt(std::max(0.0f, m2[x] - mp[x] * mp[x]));
      const float threshold = mp[x] * float(1.0 + k * (sd / 128.0 - 1.0));
      out[x] = gp[x] < threshold ? 255 : 0;
    }
  }
  return ink;
}

InkComponents FindComponents(const cv::Mat1b& ink) {
  InkComponents c;
  cv::Mat centroids;
  c.count = cv::connectedComponentsWithStats(ink, c.labels, c.stats, centroids, 8, CV_32S);
  return c;
}

}  // namespace detail

void DeclareOptions(OptionTable& table, FeaturesOptions* o) {
  table.Value("margin", &o->margin_px, 0.0, 1000.0,
              "pixels kept from the region's outline; 0 = 0.6% of the image diagonal");
  table.Value("sauvola-window", &o->sauvola_window, 0, 1001,
              "binarisation window (px); 0 = 1.5% of the image diagonal");
  table.Value("sauvola-k", &o->sauvola_k, 0.01, 1.0, "Sauvola's k");
  table.Value("bend-px", &o->bend_px, 0.1, 20.0,
              "text: cut a baseline where it leaves a line by more than this (px)...");
  table.Value("bend-rel", &o->bend_rel, 0.0, 1.0,
              "...or by this fraction of the text height, if larger");
  table.Value("bend-window", &o->bend_window, 0.0, 10.0,
              "text: judge the bend on the baseline's running median over this many text "
              "heights either way (0 = on every sample)");
  table.Value("max-gap", &o->max_gap, 0.1, 10.0, "text: largest gap chained, in text heights");
  table.Value("row-gap", &o->row_gap, 0.0, 1000.0,
              "text: join straight pieces of one baseline across gaps up to this many text "
              "heights (a receipt's item and price); 0 = off");
  table.Value("min-text-length", &o->min_text_length, 0.0, 1000.0,
              "text: shortest segment, in text heights");
  table.Value("min-length", &o->min_length_px, 0.0, 10000.0, "shortest segment of any kind (px)");
  table.Value("join-gap", &o->join_gap, 0.0, 1000.0,
              "join LSD pieces of one straight edge across gaps up to this many px (or half a "
              "text height); 0 = off");
  table.Value("lsd-upscale", &o->lsd_upscale, 0.0, 4.0,
              "run LSD on the region enlarged this many times (thin rules); 0 = 2 when the text "
              "is under 12 px high and the region under 4 MP, else 1");
  table.Switch("step-edges", &o->step_edges,
               "also keep single step edges (colour fields, shading), not only thin lines");
  table.Switch("verbose", &o->verbose, "log each step and its time");
}

FeaturesResult DetectFeatures(const cv::Mat& image, const cv::Mat& mask_in,
                              const FeaturesOptions& options) {
  if (image.empty() || image.type() != CV_8UC3) throw InputError("expected an 8-bit colour image");
  if (mask_in.size() != image.size())
    throw InputError("mask is " + std::to_string(mask_in.cols) + "x" +
                     std::to_string(mask_in.rows) + " but the image is " +
                     std::to_string(image.cols) + "x" + std::to_string(image.rows));
  if (mask_in.type() != CV_8UC1) throw InputError("mask is not an 8-bit single-channel image");
  const cv::Mat1b mask = mask_in > 127;
  if (cv::countNonZero(mask) == 0) throw InputError("mask is empty (no document region)");
  const auto start = std::chrono::steady_clock::now();
  auto step = [&](const std::string& what) {
    if (options.verbose) Log(what + " (" + Fixed(SecondsSince(start), 3) + " s)");
  };

  const double diag = std::hypot(image.cols, image.rows);
  cv::Mat1b grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  const int margin = options.margin_px > 0 ? int(std::lround(options.margin_px))
                                           : std::max(4, int(std::lround(0.006 * diag)));
  cv::Mat1b region;
  cv::erode(mask, region,
            cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * margin + 1, 2 * margin + 1)));
  const int window = (options.sauvola_window > 0 ? options.sauvola_window
                                                 : std::max(15, int(std::lround(0.015 * diag)))) |
                     1;
  cv::Mat1b ink = detail::SauvolaInk(grey, window, options.sauvola_k);
  ink &= region;
  const detail::InkComponents components = detail::FindComponents(ink);
  step("ink: " + std::to_string(components.count - 1) + " marks");
  detail::TextResult text = detail::DetectTextSegments(components, grey, image, options);
  step("text: " + std::to_string(text.segments.size()) + " segments, height " +
       Fixed(text.height, 2) + " px");
  std::vector<Segment> edges =
      detail::DetectEdgeSegments(grey, ink, components, text, region, options);
  step("edges: " + std::to_string(edges.size()) + " segments");

  FeaturesResult result;
  result.text_height = text.height;
  result.text_direction = text.direction_deg;
  result.text_upside_down = text.upside_down;
  if (text.orientation_known) result.text_down = text.down;
  result.votes_upright = text.votes_upright;
  result.votes_upside_down = text.votes_upside_down;
  step(std::string("text orientation ") + (text.orientation_known ? "" : "not ") +
       "known: outline stray " + std::to_string(text.votes_upside_down) + " px on the +n side, " +
       std::to_string(text.votes_upright) + " px on the -n side; small marks " +
       std::to_string(text.dots_upright) + " for +n, " + std::to_string(text.dots_upside_down) +
       " for -n");
  result.text_segments = int(text.segments.size());
  result.edge_segments = int(edges.size());
  result.segments = std::move(text.segments);
  result.segments.insert(result.segments.end(), edges.begin(), edges.end());
  return result;
}

Json FeaturesToJson(const FeaturesResult& r, const std::string& image_name, int width, int height,
                    const Json& options_record) {
  Json doc = MakeHeader("docunfold.features", 1, "detect-features", options_record);
  doc["image"] = image_name;
  doc["width"] = width;
  doc["height"] = height;
  doc["text_height_px"] = r.text_height;
  doc["text_direction_deg"] = r.text_direction;
  doc["text_upside_down"] = r.text_upside_down;
  if (r.text_down) doc["text_down"] = {r.text_down->x, r.text_down->y};
  doc["segments"] = Json::array();
  for (const Segment& s : r.segments) {
    Json pts = Json::array();
    for (const auto& p : s.points) pts.push_back({p.x, p.y});
    Json seg = {{"kind", s.kind}, {"points", pts}};
    if (s.kind == "text") seg["characters"] = s.characters;
    doc["segments"].push_back(seg);
  }
  return doc;
}

cv::Mat DrawFeaturesOverlay(const cv::Mat& image, const cv::Mat& mask, const FeaturesResult& r,
                            int max_size) {
  const double s = std::min(1.0, double(max_size) / std::max(image.cols, image.rows));
  cv::Mat out, small_mask;
  cv::resize(image, out, cv::Size(), s, s, cv::INTER_AREA);
  cv::resize(mask, small_mask, out.size(), 0, 0, cv::INTER_NEAREST);
  cv::Mat dark = out * 0.45;
  dark.copyTo(out, small_mask <= 127);
  const int thick = std::max(1, int(std::lround(out.cols / 800.0)));
  for (const Segment& seg : r.segments) {
    const cv::Scalar colour =
        seg.kind == "text" ? cv::Scalar(40, 40, 230) : cv::Scalar(230, 200, 0);
    for (size_t k = 1; k < seg.points.size(); ++k) {
      const cv::Point2d a = (seg.points[k - 1] + cv::Point2d(0.5, 0.5)) * s - cv::Point2d(0.5, 0.5);
      const cv::Point2d b = (seg.points[k] + cv::Point2d(0.5, 0.5)) * s - cv::Point2d(0.5, 0.5);
      cv::line(out, cv::Point(int(std::lround(a.x * 16)), int(std::lround(a.y * 16))),
               cv::Point(int(std::lround(b.x * 16)), int(std::lround(b.y * 16))), colour, thick,
               cv::LINE_AA, 4);
    }
  }
  const std::string note = std::to_string(r.text_segments) + " text (red), " +
                           std::to_string(r.edge_segments) + " edge (cyan) segments";
  cv::putText(out, note, cv::Point(10, 10 + 14 * thick), cv::FONT_HERSHEY_SIMPLEX, 0.5 * thick,
              cv::Scalar(255, 255, 255), thick, cv::LINE_AA);
  return out;
}

}  // namespace docunfold::features
