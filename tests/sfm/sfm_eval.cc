#include "tests/sfm/sfm_eval.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <nanoflann.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "common/raster.h"
#include "tests/support/test_support.h"

namespace docunfold::testing {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
  return v[v.size() / 2];
}

struct CentroidCloud {
  std::vector<Eigen::Vector3d> pts;
  size_t kdtree_get_point_count() const { return pts.size(); }
  double kdtree_get_pt(size_t i, size_t d) const { return pts[i][int(d)]; }
  template <class B>
  bool kdtree_get_bbox(B&) const {
    return false;
  }
};
using CentroidTree =
    nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, CentroidCloud>,
                                        CentroidCloud, 3, size_t>;

// Closest points on the true surface, via the triangles whose centroids are
// nearest (the true meshes have triangles of about 1 mm).
class SurfaceDistance {
 public:
  explicit SurfaceDistance(const GroundTruth& gt) : gt_(gt) {
    for (const Triangle& t : gt.triangles)
      cloud_.pts.push_back(
          (gt.mesh.vertices[t[0]] + gt.mesh.vertices[t[1]] + gt.mesh.vertices[t[2]]) / 3.0);
    tree_ =
        std::make_unique<CentroidTree>(3, cloud_, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree_->buildIndex();
  }
  double Distance(const Eigen::Vector3d& p, Eigen::Vector3d* foot = nullptr) const {
    constexpr size_t k = 12;
    size_t idx[k];
    double d2[k];
    const size_t n = tree_->knnSearch(p.data(), k, idx, d2);
    double best = 1e300;
    for (size_t i = 0; i < n; ++i) {
      const Triangle& t = gt_.triangles[idx[i]];
      Eigen::Vector3d c;
      const double d = PointTriangleDistance(p, gt_.mesh.vertices[t[0]], gt_.mesh.vertices[t[1]],
                                             gt_.mesh.vertices[t[2]], &c);
      if (d < best) {
        best = d;
        if (foot) *foot = c;
      }
    }
    return best;
  }

 private:
  const GroundTruth& gt_;
  CentroidCloud cloud_;
  std::unique_ptr<CentroidTree> tree_;
};

Eigen::Matrix4d Umeyama(const std::vector<Eigen::Vector3d>& src,
                        const std::vector<Eigen::Vector3d>& dst) {
  Eigen::Matrix3Xd a(3, src.size()), b(3, dst.size());
  for (size_t i = 0; i < src.size(); ++i) {
    a.col(i) = src[i];
    b.col(i) = dst[i];
  }
  return Eigen::umeyama(a, b, true);
}

// The similarity minimising sum w_i |s R src_i + t - dst_i|^2 (Umeyama's
// closed form with weighted means and covariance).
Eigen::Matrix4d WeightedUmeyama(const std::vector<Eigen::Vector3d>& src,
                                const std::vector<Eigen::Vector3d>& dst,
                                const std::vector<double>& w) {
  double total = 0;
  Eigen::Vector3d mean_src = Eigen::Vector3d::Zero(), mean_dst = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < src.size(); ++i) {
    total += w[i];
    mean_src += w[i] * src[i];
    mean_dst += w[i] * dst[i];
  }
  mean_src /= total;
  mean_dst /= total;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  double var_src = 0;
  for (size_t i = 0; i < src.size(); ++i) {
    cov += w[i] * (dst[i] - mean_dst) * (src[i] - mean_src).transpose();
    var_src += w[i] * (src[i] - mean_src).squaredNorm();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d sign = Eigen::Vector3d::Ones();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) sign.z() = -1;
  const Eigen::Matrix3d R = svd.matrixU() * sign.asDiagonal() * svd.matrixV().transpose();
  const double scale = svd.singularValues().dot(sign) / var_src;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = scale * R;
  T.topRightCorner<3, 1>() = mean_dst - scale * R * mean_src;
  return T;
}

Eigen::Vector3d Apply(const Eigen::Matrix4d& T, const Eigen::Vector3d& p) {
  return T.topLeftCorner<3, 3>() * p + T.topRightCorner<3, 1>();
}

}  // namespace

std::vector<fs::path> SfmDataSets() {
  std::vector<fs::path> out;
  for (const fs::path& base : {SourceDir() / "samples", RealisticDir()}) {
    std::error_code ec;
    if (base.empty() || !fs::is_directory(base, ec)) continue;
    std::vector<fs::path> here;
    for (const auto& e : fs::directory_iterator(base, ec))
      if (fs::is_regular_file(e.path() / "ground_truth" / "cameras.json") &&
          fs::is_directory(e.path() / "images"))
        here.push_back(e.path());
    std::sort(here.begin(), here.end());
    out.insert(out.end(), here.begin(), here.end());
  }
  return out;
}

std::string SfmDataSetName(const fs::path& dataset) {
  return dataset.parent_path().filename().string() + "/" + dataset.filename().string();
}

fs::path AnyDataSet() {
  const auto sets = SfmDataSets();
  return sets.empty() ? fs::path() : sets.front();
}

double PointTriangleDistance(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                             const Eigen::Vector3d& b, const Eigen::Vector3d& c,
                             Eigen::Vector3d* closest) {
  // Ericson, Real-Time Collision Detection, 5.1.5: Voronoi regions.
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  Eigen::Vector3d q;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  const double vc = d1 * d4 - d3 * d2, vb = d5 * d2 - d1 * d6, va = d3 * d6 - d5 * d4;
  if (d1 <= 0 && d2 <= 0) {
    q = a;
  } else if (d3 >= 0 && d4 <= d3) {
    q = b;
  } else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    q = a + ab * (d1 / (d1 - d3));
  } else if (d6 >= 0 && d5 <= d6) {
    q = c;
  } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    q = a + ac * (d2 / (d2 - d6));
  } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    q = b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  } else {
    const double denom = 1.0 / (va + vb + vc);
    q = a + ab * (vb * denom) + ac * (vc * denom);
  }
  if (closest) *closest = q;
  return (p - q).norm();
}

std::vector<TrueViewFigures> TrueViews(const GroundTruth& gt) {
  std::vector<TrueViewFigures> out;
  for (const PinholeCamera& cam : gt.cameras.views) {
    const double scale = 400.0 / std::max(cam.width, cam.height);
    const RasterResult r = RasterizeMesh(cam, gt.mesh.vertices, gt.triangles, scale);
    const Eigen::Vector3d center = cam.Center();
    std::vector<double> cosines;
    bool touches = false;
    for (int y = 0; y < r.face.rows; ++y)
      for (int x = 0; x < r.face.cols; ++x) {
        const int f = r.face(y, x);
        if (f < 0) continue;
        if (x == 0 || y == 0 || x == r.face.cols - 1 || y == r.face.rows - 1) touches = true;
        const Triangle& t = gt.triangles[f];
        const Eigen::Vector3d& a = gt.mesh.vertices[t[0]];
        const Eigen::Vector3d n =
            (gt.mesh.vertices[t[1]] - a).cross(gt.mesh.vertices[t[2]] - a).normalized();
        const Eigen::Vector3d ray = ((a - center)).normalized();
        cosines.push_back(std::abs(n.dot(ray)));
      }
    TrueViewFigures v;
    v.image = cam.image;
    v.frontality = Median(cosines);
    // Resolution per triangle, weighted by its area on the page; visible
    // when its centre is the nearest surface at its pixel.
    const RasterResult full = RasterizeMesh(cam, gt.mesh.vertices, gt.triangles, 1.0);
    std::vector<std::pair<double, double>> resolution;  // (px per unit, area)
    for (const Triangle& t : gt.triangles) {
      const Eigen::Vector3d& a = gt.mesh.vertices[t[0]];
      const Eigen::Vector3d& b = gt.mesh.vertices[t[1]];
      const Eigen::Vector3d& c = gt.mesh.vertices[t[2]];
      const Eigen::Vector3d cross = (b - a).cross(c - a);
      const double area = 0.5 * cross.norm();
      if (!(area > 0)) continue;
      const Eigen::Vector3d centre = (a + b + c) / 3;
      const Eigen::Vector3d xc = cam.CamFromWorld(centre);
      double value = 0;
      if (xc.z() > 0) {
        const Eigen::Vector2d px = cam.ProjectCam(xc);
        const int x = int(std::lround(px.x())), y = int(std::lround(px.y()));
        if (x >= 0 && y >= 0 && x < full.depth.cols && y < full.depth.rows &&
            xc.z() <= full.depth(y, x) * 1.01) {
          const double cosine = std::abs(cross.normalized().dot((centre - center).normalized()));
          value = cam.K(0, 0) * cosine / xc.z();
        }
      }
      resolution.push_back({value, area});
    }
    std::sort(resolution.begin(), resolution.end());
    double total = 0, acc = 0;
    for (const auto& r : resolution) total += r.second;
    for (const auto& r : resolution) {
      acc += r.second;
      if (acc >= 0.1 * total) {
        v.resolution = r.first;
        break;
      }
    }
    v.whole_page = !touches && !cosines.empty();
    out.push_back(v);
  }
  return out;
}

SfmFigures MeasureSfm(const fs::path& sfm_dir, const GroundTruth& gt) {
  SfmFigures f;
  const CameraSet sfm = ReadCameras(sfm_dir / "cameras.json");
  const PlyData ply = ReadPly(sfm_dir / "points.ply");
  const double diag = gt.Diagonal();
  f.views = int(gt.cameras.views.size());
  f.reference = sfm.reference;
  f.points = int(ply.vertices.size());

  std::vector<Eigen::Vector3d> src, dst;
  for (const PinholeCamera& c : sfm.views)
    if (const PinholeCamera* t = gt.cameras.Find(c.image)) {
      src.push_back(c.Center());
      dst.push_back(t->Center());
    }
  f.registered = int(src.size());
  if (src.size() < 3) return f;
  // Centres alone leave the rotation about their centroid weakly held when
  // there are few views, and the page, half a metre in front of them, moves
  // with it: add each camera's point at the page's distance along its
  // optical axis (the true distance, and that over the centres' scale on
  // sfm's side), so the cameras' orientations hold it too.
  Eigen::Matrix4d T = Umeyama(src, dst);
  std::vector<Eigen::Vector3d> axis_src = src, axis_dst = dst;
  {
    Eigen::Vector3d page_centre = Eigen::Vector3d::Zero();
    for (const auto& v : gt.mesh.vertices) page_centre += v / double(gt.mesh.vertices.size());
    const double scale = T.block<3, 1>(0, 0).norm();
    for (const PinholeCamera& c : sfm.views)
      if (const PinholeCamera* t = gt.cameras.Find(c.image)) {
        const double d = (page_centre - t->Center()).norm();
        axis_dst.push_back(t->Center() + d * t->R.row(2).transpose());
        axis_src.push_back(c.Center() + d / scale * c.R.row(2).transpose());
      }
    T = Umeyama(axis_src, axis_dst);
  }
  double sum = 0;
  for (size_t i = 0; i < src.size(); ++i) sum += (Apply(T, src[i]) - dst[i]).squaredNorm();
  f.camera_rms = std::sqrt(sum / src.size()) / diag;

  // A point is the page's when it falls on the true page in at least half
  // of the true views whose image it falls in: table points hidden behind
  // the page in one view are beside it in the others.
  const SurfaceDistance surface(gt);
  std::vector<cv::Mat1b> masks;
  for (const PinholeCamera& c : gt.cameras.views) masks.push_back(TruePageMask(gt, c));
  std::vector<double> all, page;
  std::vector<Eigen::Vector3d> page_points;
  for (const Eigen::Vector3d& p : ply.vertices) {
    const Eigen::Vector3d x = Apply(T, p);
    const double d = surface.Distance(x) / diag;
    all.push_back(d);
    int in_image = 0, on_page = 0;
    for (size_t v = 0; v < gt.cameras.views.size(); ++v) {
      const PinholeCamera& c = gt.cameras.views[v];
      const Eigen::Vector3d xc = c.CamFromWorld(x);
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d px = c.ProjectCam(xc);
      const int u = int(std::lround(px.x())), w = int(std::lround(px.y()));
      if (u < 0 || w < 0 || u >= masks[v].cols || w >= masks[v].rows) continue;
      ++in_image;
      on_page += masks[v](w, u) != 0;
    }
    if (in_image == 0 || 2 * on_page < in_image) continue;
    page.push_back(d);
    page_points.push_back(x);
  }
  f.page_points = int(page.size());
  f.median_all_distance = Median(all);
  f.median_page_distance = Median(page);

  // Trimmed ICP of the page points onto the surface, from T; with
  // `cameras` the camera pairs (centres and axis points, as in T) weigh as
  // much as the points together, so the fit holds both.
  auto fit = [&](bool cameras, double* median, double* camera_rms) {
    std::vector<Eigen::Vector3d> cur = page_points;
    Eigen::Matrix4d icp = Eigen::Matrix4d::Identity();
    for (int iter = 0; iter < 15; ++iter) {
      std::vector<std::pair<double, size_t>> order;
      std::vector<Eigen::Vector3d> feet(cur.size());
      for (size_t i = 0; i < cur.size(); ++i)
        order.push_back({surface.Distance(cur[i], &feet[i]), i});
      std::sort(order.begin(), order.end());
      std::vector<Eigen::Vector3d> a, b;
      for (size_t k = 0; k < order.size() * 8 / 10; ++k) {
        a.push_back(cur[order[k].second]);
        b.push_back(feet[order[k].second]);
      }
      std::vector<double> w(a.size(), 1.0);
      if (cameras) {
        const double share = double(a.size()) / double(axis_src.size());
        for (size_t i = 0; i < axis_src.size(); ++i) {
          a.push_back(Apply(icp * T, axis_src[i]));
          b.push_back(axis_dst[i]);
          w.push_back(share);
        }
      }
      const Eigen::Matrix4d S = WeightedUmeyama(a, b, w);
      for (Eigen::Vector3d& p : cur) p = Apply(S, p);
      icp = S * icp;
    }
    std::vector<double> d;
    for (const Eigen::Vector3d& p : cur) d.push_back(surface.Distance(p) / diag);
    *median = Median(d);
    double sum = 0;
    for (size_t i = 0; i < src.size(); ++i) sum += (Apply(icp * T, src[i]) - dst[i]).squaredNorm();
    *camera_rms = std::sqrt(sum / src.size()) / diag;
  };
  if (page_points.size() >= 10) {
    double unused = 0;
    fit(false, &f.shape_median_distance, &unused);
    fit(true, &f.joint_median_distance, &f.joint_camera_rms);
  }

  const auto truth = TrueViews(gt);
  for (const TrueViewFigures& v : truth) {
    if (v.image == sfm.reference) {
      f.reference_frontality = v.frontality;
      f.reference_resolution = v.resolution;
      f.reference_whole_page = v.whole_page;
    }
    if (v.whole_page && v.resolution > f.best_true_resolution) {
      f.best_true_resolution = v.resolution;
      f.best_true_view = v.image;
    }
  }
  if (const PinholeCamera* ref = sfm.Find(sfm.reference)) {
    std::vector<double> depths;
    for (const Eigen::Vector3d& p : ply.vertices) {
      const Eigen::Vector3d xc = ref->CamFromWorld(p);
      if (xc.z() <= 0) continue;
      const Eigen::Vector2d px = ref->ProjectCam(xc);
      if (px.x() >= 0 && px.y() >= 0 && px.x() <= ref->width - 1 && px.y() <= ref->height - 1)
        depths.push_back(xc.z());
    }
    f.reference_median_depth = Median(depths);
  }
  return f;
}

std::string FormatFigures(const SfmFigures& f) {
  char buf[768];
  std::snprintf(buf, sizeof buf,
                "registered %d/%d, camera centres RMS %.3f%%, points %d (on page %d), "
                "median distance page points %.3f%% (all %.3f%%, shape after ICP %.3f%%; fitting "
                "cameras and page together: cameras %.3f%%, "
                "page points %.3f%%), "
                "reference %s (true frontality %.3f, resolution %.0f px/m, whole page %s; "
                "best-resolving whole view %s %.0f)",
                f.registered, f.views, 100 * f.camera_rms, f.points, f.page_points,
                100 * f.median_page_distance, 100 * f.median_all_distance,
                100 * f.shape_median_distance, 100 * f.joint_camera_rms,
                100 * f.joint_median_distance, f.reference.c_str(), f.reference_frontality,
                f.reference_resolution, f.reference_whole_page ? "yes" : "no",
                f.best_true_view.c_str(), f.best_true_resolution);
  return buf;
}

fs::path MakeSmallDataSet(const fs::path& dataset, const fs::path& dir, int count, int width) {
  fs::create_directories(dir / "images");
  std::vector<fs::path> photos;
  for (const auto& e : fs::directory_iterator(dataset / "images")) photos.push_back(e.path());
  std::sort(photos.begin(), photos.end());
  for (int i = 0; i < count && i < int(photos.size()); ++i) {
    cv::Mat im = cv::imread(photos[i].string());
    cv::Mat small;
    cv::resize(im, small, cv::Size(width, int(std::lround(im.rows * double(width) / im.cols))), 0,
               0, cv::INTER_AREA);
    cv::imwrite((dir / "images" / photos[i].filename()).replace_extension(".jpg").string(), small,
                {cv::IMWRITE_JPEG_QUALITY, 92});
  }
  return dir;
}

}  // namespace docunfold::testing
