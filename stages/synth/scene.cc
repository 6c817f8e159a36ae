#include "stages/synth/scene.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

#include "stages/synth/random.h"

namespace docunfold::synth {
namespace {

double Radians(double deg) { return deg * kPi / 180; }

// Smooth random field in [-1, 1] of the given size.
cv::Mat1f LowFrequency(cv::Size size, int cells, std::mt19937* rng) {
  cv::Mat1f coarse(cells, cells);
  for (float& v : coarse) v = float(Uniform(rng, -1, 1));
  cv::Mat1f out;
  cv::resize(coarse, out, size, 0, 0, cv::INTER_CUBIC);
  return out;
}

cv::Mat1f FineNoise(cv::Size size, double sigma, std::mt19937* rng) {
  cv::Mat1f noise(size);
  cv::RNG cv_rng((*rng)());
  cv_rng.fill(noise, cv::RNG::NORMAL, 0, sigma);
  return noise;
}

PinholeCamera LookAt(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
                     const Eigen::Vector3d& up_hint, double roll, const Eigen::Matrix3d& K,
                     int width, int height) {
  const Eigen::Vector3d forward = (target - eye).normalized();
  Eigen::Vector3d x = forward.cross(up_hint).normalized();
  Eigen::Vector3d y = forward.cross(x);
  const Eigen::Vector3d xr = std::cos(roll) * x + std::sin(roll) * y;
  const Eigen::Vector3d yr = -std::sin(roll) * x + std::cos(roll) * y;
  PinholeCamera cam;
  cam.width = width;
  cam.height = height;
  cam.K = K;
  cam.R.row(0) = xr.transpose();
  cam.R.row(1) = yr.transpose();
  cam.R.row(2) = forward.transpose();
  cam.t = -cam.R * eye;
  return cam;
}

struct Extent {
  double ratio;            // page extent relative to the image, larger axis
  double inside_fraction;  // of the vertices, inside the image
  bool all_inside_margin;  // every vertex at least 3% inside the border
};

Extent Measure(const PageSurface& page, const PinholeCamera& cam) {
  double x0 = 1e18, x1 = -1e18, y0 = 1e18, y1 = -1e18;
  int inside = 0;
  bool margin_ok = true;
  const double mx = 0.03 * cam.width, my = 0.03 * cam.height;
  for (const Eigen::Vector3d& v : page.vertices) {
    const Eigen::Vector3d xc = cam.CamFromWorld(v);
    if (xc.z() <= 0) {
      margin_ok = false;
      continue;
    }
    const Eigen::Vector2d p = cam.ProjectCam(xc);
    x0 = std::min(x0, p.x());
    x1 = std::max(x1, p.x());
    y0 = std::min(y0, p.y());
    y1 = std::max(y1, p.y());
    if (p.x() >= 0 && p.y() >= 0 && p.x() <= cam.width - 1 && p.y() <= cam.height - 1) ++inside;
    if (p.x() < mx || p.y() < my || p.x() > cam.width - 1 - mx || p.y() > cam.height - 1 - my)
      margin_ok = false;
  }
  return {std::max((x1 - x0) / cam.width, (y1 - y0) / cam.height),
          double(inside) / page.vertices.size(), margin_ok};
}

}  // namespace

std::string BackgroundName(Background b) {
  switch (b) {
    case Background::kPlain:
      return "plain";
    case Background::kWood:
      return "wood";
    case Background::kCloth:
      return "cloth";
    case Background::kGranite:
      return "granite";
  }
  return "plain";
}

std::vector<PinholeCamera> MakeCameras(const PageSurface& page, const CameraOptions& options,
                                       std::mt19937* rng) {
  const double hfov = Radians(Uniform(rng, options.hfov_min_deg, options.hfov_max_deg));
  const double f = (options.width / 2.0) / std::tan(hfov / 2);
  Eigen::Matrix3d K;
  K << f, 0, (options.width - 1) / 2.0, 0, f, (options.height - 1) / 2.0, 0, 0, 1;

  Eigen::Vector3d lo = page.vertices[0], hi = lo;
  for (const auto& v : page.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Vector3d centre = (lo + hi) / 2;
  const double diag = (hi - lo).head<2>().norm();
  // For a cut-off page every view aims beyond one side of the page.
  const double cut_dir = Uniform(rng, 0, 2 * kPi);
  const double base_azimuth = Uniform(rng, 0, 2 * kPi);

  std::vector<PinholeCamera> cameras;
  for (int i = 0; i < options.views; ++i) {
    const double azimuth = base_azimuth + 2 * kPi * i / options.views + Uniform(rng, -0.3, 0.3);
    const double top = options.elevation_max_deg, bottom = options.elevation_min_deg;
    const double elevation = Radians(i == 0 ? Uniform(rng, std::max(bottom, top - 8), top)
                                            : Uniform(rng, bottom, std::max(bottom, top - 6)));
    const double roll = Radians(Uniform(rng, -10, 10));
    Eigen::Vector3d target = centre + Eigen::Vector3d(Uniform(rng, -0.03, 0.03) * diag,
                                                      Uniform(rng, -0.03, 0.03) * diag, 0);
    double fill = Uniform(rng, options.fill_min, options.fill_max);
    if (options.cut_off) {
      target += 0.22 * diag * Eigen::Vector3d(std::cos(cut_dir), std::sin(cut_dir), 0);
      fill = Uniform(rng, 1.05, 1.2);
    }
    const Eigen::Vector3d dir(std::cos(elevation) * std::cos(azimuth),
                              std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
    const Eigen::Vector3d up_hint(-std::cos(azimuth), -std::sin(azimuth), 0);
    double distance = diag / (2 * std::tan(hfov / 2) * fill);
    PinholeCamera cam;
    for (int it = 0; it < 6; ++it) {
      cam =
          LookAt(target + distance * dir, target, up_hint, roll, K, options.width, options.height);
      distance *= Measure(page, cam).ratio / fill;
    }
    cam = LookAt(target + distance * dir, target, up_hint, roll, K, options.width, options.height);
    for (int it = 0; it < 40; ++it) {
      const Extent e = Measure(page, cam);
      const bool ok = options.cut_off ? (e.inside_fraction > 0.6 && e.inside_fraction < 0.93)
                                      : e.all_inside_margin;
      if (ok) break;
      distance *= (options.cut_off && e.inside_fraction >= 0.93) ? 0.96 : 1.05;
      cam =
          LookAt(target + distance * dir, target, up_hint, roll, K, options.width, options.height);
    }
    cam.image = "view_" + std::string(i < 10 ? "0" : "") + std::to_string(i) + ".jpg";
    cameras.push_back(cam);
  }
  return cameras;
}

Lighting RandomLighting(std::mt19937* rng) {
  Lighting l;
  const double elevation = Radians(Uniform(rng, 35, 70));
  const double azimuth = Uniform(rng, 0, 2 * kPi);
  l.direction = Eigen::Vector3d(std::cos(elevation) * std::cos(azimuth),
                                std::cos(elevation) * std::sin(azimuth), std::sin(elevation));
  l.ambient = Uniform(rng, 0.35, 0.5);
  l.diffuse = Uniform(rng, 0.55, 0.7);
  return l;
}

Table MakeTable(Background background, std::mt19937* rng) {
  Table table;
  table.extent = 1.0;
  table.metres_per_pixel = 0.001;
  const int n = int(2 * table.extent / table.metres_per_pixel);
  const cv::Size size(n, n);
  cv::Mat3f img(size);
  const cv::Mat1f low = LowFrequency(size, 20, rng);
  const cv::Mat1f fine = FineNoise(size, 1.0, rng);
  switch (background) {
    case Background::kPlain: {
      const float v = float(Uniform(rng, 90, 170));
      const cv::Vec3f base(v * float(Uniform(rng, 0.85, 1.0)), v * float(Uniform(rng, 0.9, 1.0)),
                           v * float(Uniform(rng, 0.9, 1.1)));
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          img(y, x) = base * (1 + 0.06f * low(y, x)) + cv::Vec3f::all(4 * fine(y, x));
      break;
    }
    case Background::kWood: {
      const cv::Vec3f base(float(Uniform(rng, 40, 70)), float(Uniform(rng, 75, 110)),
                           float(Uniform(rng, 120, 160)));
      const double period = Uniform(rng, 0.004, 0.009) / table.metres_per_pixel;
      const double plank = Uniform(rng, 0.12, 0.2) / table.metres_per_pixel;
      const cv::Mat1f warp = LowFrequency(size, 12, rng);
      const double angle = Uniform(rng, 0, kPi);
      const double ca = std::cos(angle), sa = std::sin(angle);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const double along = ca * x + sa * y, across = -sa * x + ca * y;
          const double grain = std::sin(2 * kPi * (across / period + 2.5 * warp(y, x)));
          const bool gap = std::fmod(std::abs(across), plank) < 2.0;
          float k = float(1 + 0.12 * grain + 0.08 * low(y, x) + 0.03 * std::sin(along * 0.05));
          if (gap) k *= 0.55f;
          img(y, x) = base * k + cv::Vec3f::all(5 * fine(y, x));
        }
      break;
    }
    case Background::kCloth: {
      const cv::Vec3f colours[] = {{70, 110, 60}, {110, 70, 50}, {60, 60, 120}, {90, 90, 90}};
      const cv::Vec3f base = colours[(*rng)() % 4] * float(Uniform(rng, 0.8, 1.2));
      const double weave = Uniform(rng, 0.8, 1.6);  // pixels = millimetres here
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x) {
          const float w =
              float(0.06 * std::sin(2 * kPi * x / weave) * std::sin(2 * kPi * y / weave));
          img(y, x) = base * (1 + w + 0.07f * low(y, x)) + cv::Vec3f::all(6 * fine(y, x));
        }
      break;
    }
    case Background::kGranite: {
      const float v = float(Uniform(rng, 80, 140));
      cv::Mat1f speckle = FineNoise(size, 1.0, rng);
      cv::GaussianBlur(speckle, speckle, cv::Size(0, 0), 1.2);
      for (int y = 0; y < n; ++y)
        for (int x = 0; x < n; ++x)
          img(y, x) =
              cv::Vec3f::all(v * (1 + 0.05f * low(y, x)) + 90 * speckle(y, x)) + cv::Vec3f(0, 2, 6);
      break;
    }
  }
  img.convertTo(table.image, CV_8UC3);
  return table;
}

cv::Mat RenderView(const PageSurface& page, const cv::Mat& page_texture, const Table& table,
                   const Lighting& light, const PinholeCamera& camera) {
  const double ss = std::min(2.0, 6400.0 / camera.width);
  const int W = int(std::lround(camera.width * ss)), H = int(std::lround(camera.height * ss));

  // Smooth per-vertex normals of the printed side, from the grid.
  std::vector<Eigen::Vector3d> normals(page.vertices.size());
  auto at = [&](int r, int c) {
    return page.vertices[std::clamp(r, 0, page.ny - 1) * page.nx + std::clamp(c, 0, page.nx - 1)];
  };
  for (int r = 0; r < page.ny; ++r)
    for (int c = 0; c < page.nx; ++c)
      normals[r * page.nx + c] =
          (at(r + 1, c) - at(r - 1, c)).cross(at(r, c + 1) - at(r, c - 1)).normalized();

  RasterResult page_raster = RasterizeMesh(camera, page.vertices, page.triangles, ss);
  Eigen::MatrixXf attributes(page.vertices.size(), 6);
  for (size_t i = 0; i < page.vertices.size(); ++i) {
    attributes(i, 0) = float(page.st[i].x() * page_texture.cols - 0.5);
    attributes(i, 1) = float(page.st[i].y() * page_texture.rows - 0.5);
    for (int k = 0; k < 3; ++k) attributes(i, 2 + k) = float(normals[i][k]);
    attributes(i, 5) = 0;
  }
  cv::Mat page_attr = InterpolateAttributes(page_raster, page.triangles, attributes);

  // The table: a fine grid so that triangles behind the camera drop out
  // without losing the visible part.
  const int tn = 48;
  std::vector<Eigen::Vector3d> table_vertices;
  std::vector<Triangle> table_triangles;
  for (int r = 0; r <= tn; ++r)
    for (int c = 0; c <= tn; ++c)
      table_vertices.emplace_back(-table.extent + 2 * table.extent * c / tn,
                                  -table.extent + 2 * table.extent * r / tn, 0.0);
  for (int r = 0; r < tn; ++r)
    for (int c = 0; c < tn; ++c) {
      const int a = r * (tn + 1) + c;
      table_triangles.push_back({a, a + 1, a + tn + 2});
      table_triangles.push_back({a, a + tn + 2, a + tn + 1});
    }
  RasterResult table_raster = RasterizeMesh(camera, table_vertices, table_triangles, ss);
  Eigen::MatrixXf table_xy(table_vertices.size(), 2);
  for (size_t i = 0; i < table_vertices.size(); ++i) {
    table_xy(i, 0) = float((table_vertices[i].x() + table.extent) / table.metres_per_pixel - 0.5);
    table_xy(i, 1) = float((table_vertices[i].y() + table.extent) / table.metres_per_pixel - 0.5);
  }
  cv::Mat table_map = InterpolateAttributes(table_raster, table_triangles, table_xy);

  // The page's shadow on the table: the page projected along the light.
  std::vector<Eigen::Vector3d> shadow_vertices;
  for (const Eigen::Vector3d& v : page.vertices)
    shadow_vertices.push_back(v - light.direction * (v.z() / light.direction.z()));
  RasterResult shadow_raster = RasterizeMesh(camera, shadow_vertices, page.triangles, ss);
  cv::Mat1f shadow;
  cv::Mat1b(shadow_raster.face >= 0).convertTo(shadow, CV_32F, 1.0 / 255);
  cv::GaussianBlur(shadow, shadow, cv::Size(0, 0), 2.5 * ss);

  // Colours of the page texture and the table, then shading.
  std::vector<cv::Mat> page_ch, table_ch;
  cv::split(page_attr, page_ch);
  cv::split(table_map, table_ch);
  cv::Mat page_map_x = page_ch[0].clone(), page_map_y = page_ch[1].clone();
  cv::Mat albedo_page, albedo_table;
  cv::remap(page_texture, albedo_page, page_map_x, page_map_y, cv::INTER_LINEAR,
            cv::BORDER_REPLICATE);
  cv::remap(table.image, albedo_table, table_ch[0], table_ch[1], cv::INTER_LINEAR,
            cv::BORDER_REFLECT);
  const cv::Vec3b paper_back = page_texture.at<cv::Vec3b>(2, 2);
  // K^-1 once per view (the same numbers as camera.CamRay, which inverts K
  // at every pixel: measurably slower over a supersampled photo).
  const Eigen::Matrix3d K_inv = camera.K.inverse();

  cv::Mat3f out(H, W);
  const double table_shade = light.ambient + light.diffuse * std::max(0.0, light.direction.z());
  for (int y = 0; y < H; ++y) {
    for (int x = 0; x < W; ++x) {
      const float dp = page_raster.depth(y, x), dt = table_raster.depth(y, x);
      cv::Vec3f colour(60, 60, 60);  // beyond the table
      if (page_raster.face(y, x) >= 0 && dp <= dt) {
        const cv::Vec6f a = page_attr.at<cv::Vec6f>(y, x);
        Eigen::Vector3d n(a[2], a[3], a[4]);
        n.normalize();
        // Viewing ray of this pixel in the world (pixel centres of the
        // supersampled raster map back to the camera's pixels).
        const Eigen::Vector3d ray =
            camera.R.transpose() *
            (K_inv * Eigen::Vector3d((x + 0.5) / ss - 0.5, (y + 0.5) / ss - 0.5, 1));
        const bool front = n.dot(ray) < 0;
        if (!front) n = -n;
        const double shade = light.ambient + light.diffuse * std::max(0.0, n.dot(light.direction));
        const cv::Vec3b c = front ? albedo_page.at<cv::Vec3b>(y, x) : paper_back;
        colour = cv::Vec3f(c[0], c[1], c[2]) * float(shade);
      } else if (table_raster.face(y, x) >= 0) {
        const cv::Vec3b c = albedo_table.at<cv::Vec3b>(y, x);
        const double shade = table_shade - shadow(y, x) * light.diffuse * light.direction.z();
        colour = cv::Vec3f(c[0], c[1], c[2]) * float(shade);
      }
      out(y, x) = colour;
    }
  }
  cv::Mat3f small;
  cv::resize(out, small, cv::Size(camera.width, camera.height), 0, 0, cv::INTER_AREA);
  cv::Mat image;
  small.convertTo(image, CV_8UC3);
  return image;
}

void AddSensorEffects(cv::Mat* image, const RenderOptions& options, std::mt19937* rng) {
  cv::Mat3f f;
  image->convertTo(f, CV_32FC3);
  if (options.blur_sigma > 0) cv::GaussianBlur(f, f, cv::Size(0, 0), options.blur_sigma);
  // Vignetting, as phone lenses have.
  const double cx = (f.cols - 1) / 2.0, cy = (f.rows - 1) / 2.0;
  const double r2max = cx * cx + cy * cy;
  const float strength = float(Uniform(rng, 0.08, 0.18));
  for (int y = 0; y < f.rows; ++y)
    for (int x = 0; x < f.cols; ++x) {
      const double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / r2max;
      f(y, x) *= 1 - strength * float(r2);
    }
  if (options.noise_sigma > 0) {
    cv::Mat3f noise(f.size());
    cv::RNG cv_rng((*rng)());
    cv_rng.fill(noise, cv::RNG::NORMAL, 0, options.noise_sigma);
    f += noise;
  }
  f.convertTo(*image, CV_8UC3);
}

}  // namespace docunfold::synth
