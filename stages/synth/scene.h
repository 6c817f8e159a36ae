// The photographed scene: the folded page resting on a textured table, lit
// by a directional light plus ambient, seen by pinhole cameras with sensor
// noise and JPEG compression.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <random>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/raster.h"

namespace docunfold::synth {

// The page surface in world coordinates (metres, z up, the table at z = 0):
// a row-major grid with page coordinates s, t in [0, 1] per vertex.
struct PageSurface {
  int nx = 0, ny = 0;
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector2d> st;
  std::vector<Triangle> triangles;
  std::vector<std::vector<int>> quads;
};

enum class Background { kPlain, kWood, kCloth, kGranite };
std::string BackgroundName(Background b);

struct CameraOptions {
  int views = 5;
  int width = 1600, height = 1200;              // pixels
  double hfov_min_deg = 65, hfov_max_deg = 75;  // one phone camera for all views
  double elevation_min_deg = 55, elevation_max_deg = 88;
  double fill_min = 0.6, fill_max = 0.82;  // page extent / image extent
  // Frame every view so that part of the page is outside the image.
  bool cut_off = false;
};

// Cameras looking down at the page from around it; view 0 is the most
// frontal. All share K (one phone camera).
std::vector<PinholeCamera> MakeCameras(const PageSurface& page, const CameraOptions& options,
                                       std::mt19937* rng);

struct RenderOptions {
  Background background = Background::kPlain;
  double noise_sigma = 2.0;  // grey levels, Gaussian, per channel
  int jpeg_quality = 90;
  double blur_sigma = 0.6;  // pixels, lens softness
};

struct Lighting {
  Eigen::Vector3d direction;  // unit, from the surface towards the light
  double ambient = 0.45;
  double diffuse = 0.6;
};

Lighting RandomLighting(std::mt19937* rng);

// A table texture covering [-extent, extent]^2 metres around the origin.
struct Table {
  cv::Mat image;  // 8-bit BGR
  double metres_per_pixel = 0.001;
  double extent = 0.6;
};
Table MakeTable(Background background, std::mt19937* rng);

// Renders one photo (8-bit BGR, camera size) before noise and JPEG.
cv::Mat RenderView(const PageSurface& page, const cv::Mat& page_texture, const Table& table,
                   const Lighting& light, const PinholeCamera& camera);

// Sensor blur and noise, deterministic for the generator's state.
void AddSensorEffects(cv::Mat* image, const RenderOptions& options, std::mt19937* rng);

}  // namespace docunfold::synth
