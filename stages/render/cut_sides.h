// Where the page ends past the border of a reference image that cuts it
// off. The reference view alone cannot tell: its mesh stops at the image
// border. The other photos often see further: the surface is continued past
// the mesh border (straight on, in M and M' alike), projected into each
// other view, and the page edge is where it leaves that view's page mask.
// The same continuation, projected into the reference's own outline, reaches
// a real side that M stops short of (render_crop.cc).
#pragma once

#include <Eigen/Core>
#include <array>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "common/camera.h"
#include "common/grid_mesh.h"

namespace docunfold::render {

namespace fs = std::filesystem;

// Where the output's pixels lie on M' (turned): pixel (x, y)'s centre is the
// point origin + ((x + 0.5) / scale.x(), (y + 0.5) / scale.y()). The two
// scales differ by under half a pixel over the crop, so that the crop's
// edges are the image's edges.
struct PixelFrame {
  Eigen::Vector2d origin = Eigen::Vector2d::Zero();
  Eigen::Vector2d scale = Eigen::Vector2d::Ones();  // output pixels per unit of M', along x and y
  Eigen::Vector2d ToPixel(const Eigen::Vector2d& p) const {
    return (p - origin).cwiseProduct(scale) - Eigen::Vector2d(0.5, 0.5);
  }
};

// The page region found in another view (20_boundary/views/<name>/mask.png).
struct ViewMask {
  PinholeCamera camera;
  cv::Mat1b mask;  // non-zero = page, camera.width x camera.height
  fs::path file;
  fs::path photo;  // the view's photo (empty: not known, not textured from)
  // The photo's lens distortion (OpenCV k1 k2 p1 p2; cameras.json): the
  // masks and photos are of the original, not undistorted, images.
  std::array<double, 4> distortion{};
};

struct CutSideOptions {
  // How far past the mesh border the surface is continued, as a fraction of
  // the visible part's extent along that axis (1: the page may be up to
  // twice what the reference view shows of it).
  double max_extension = 1.0;
  // The continuation is the straight line through each border vertex and
  // the vertex this fraction of the grid's rows (columns) inwards: far
  // enough to average out the last rows' noise, near enough to stay on the
  // panel next to the border.
  double base_fraction = 0.1;
  // Photo pixels this close to a photo's own border tell nothing: the page
  // may be cut off there too, and a mask is least sure at the image border.
  // Fraction of the photo's diagonal (0.01: 20 px at 1600x1200).
  double frame_margin = 0.01;
  // A crossing counts when the continued surface stays on the table for
  // this many photo pixels past it (a notch in the mask is not the edge).
  double confirm_px = 12;
  // Where no view sees the edge: the quantile, over the border's columns, of
  // how far past the side the views see page (0.9: the far end, less the
  // odd column where a mask or the continued surface runs wide).
  double seen_quantile = 0.9;
  // Fewest crossings of the page edge (border columns times views) that
  // place it.
  int min_crossings = 8;
  // Rows of the extension strip handed to render (its texture).
  int strip_rows = 32;
  // Rows of the strip that run back over the mesh, as far as the inner
  // vertex of base_fraction.
  int band_rows = 8;
  // When set, views[0] is the reference's own outline (a real side M stops
  // short of) and the bound is the crossings' median in one view: the one
  // whose rays meet the continued surface most squarely (a depth error d of
  // the continuation moves a crossing by d times tan of that angle), as long
  // as it sees the edge along at least half as many border columns as the
  // reference and its bound lies within max_view_disagreement of the page's
  // extent of the reference's; farther apart, the straight continuation does not
  // follow the page (a crease past M's border), and the reference's stands.
  bool squarest_view = false;
  double max_view_disagreement = 0.015;
};

// How another view's texture was moved onto the reference's.
struct ViewRegistration {
  int view = -1;
  cv::Matx23d affine = cv::Matx23d(1, 0, 0, 0, 1, 0);  // output pixels
  int inliers = 0;                                     // SIFT matches that agree on it
  bool moved = false;    // the map was applied (it improved the agreement)
  double agreement = 0;  // correlation of fine detail with the reference
  bool used = false;     // agreement high enough for the view to be used
};

// The surface continued past a cut side up to its page edge, as a grid of
// `cols` x `rows` vertices: column k runs out from the mesh border's vertex
// k; its first CutSideOptions::band_rows rows run back over the mesh (where
// the other views' texture is registered with the reference's), the next
// lies on the border. Row-major like QuadGrid.
struct ExtensionStrip {
  int cols = 0;
  int rows = 0;
  std::vector<Eigen::Vector3d> mesh3d;  // M continued (world frame)
  std::vector<Eigen::Vector2d> flat;    // M' continued (turned as `flat`)
};

// Index into a box (x0 y0 x1 y1) of the coordinate that bounds side `side`
// (0 top: y0, 1 right: x1, 2 bottom: y1, 3 left: x0).
inline int BoxIndexOfSide(int side) { return side == 0 ? 1 : side == 1 ? 2 : side == 2 ? 3 : 0; }

struct CutSideEdge {
  bool measured = false;
  // The page edge's coordinate in M' as render turns it (y for top and
  // bottom, x for left and right), and how far it lies past the visible box.
  double bound = 0;
  double extension = 0;
  // True: the bound is where the other views see the page edge (median of
  // the crossings); false: no view sees the edge, and the bound is how far
  // they see page (CutSideOptions::seen_quantile over the border's columns
  // of the farthest).
  bool edge_seen = false;
  int crossings = 0;     // border columns (in all views) that saw the edge
  int columns_seen = 0;  // border columns some view sees page past
  int views = 0;         // views with at least one crossing
  // With CutSideOptions::squarest_view: the photo whose crossings placed
  // the bound (empty: views[0], the reference), and the median |cos| of its
  // rays there.
  std::string placed_by;
  double placed_by_cos = 0;
  std::string note;      // why it was not measured
  ExtensionStrip strip;  // when measured and extension > 0
};

// How far along the surface a unit error in M's depth moves the point a ray
// meets, at |cos| `c` between ray and normal: tan of the angle.
double AlongSurface(double c);

// For each side i (0 top, 1 right, 2 bottom, 3 left of M' turned as
// `flat`) with cut[i] set: the page edge past that side of the mesh, seen in
// `views`. `flat` is M' after render's deskew turn, `visible_box` (x0 y0 x1
// y1) the box of the part of it the reference view sees.
std::array<CutSideEdge, 4> FindCutSideEdges(const MeshPair& meshes,
                                            const std::vector<Eigen::Vector2d>& flat,
                                            const Eigen::Vector4d& visible_box,
                                            const std::array<bool, 4>& cut,
                                            const std::vector<ViewMask>& views,
                                            const CutSideOptions& options = {});

// Textures the extension strips from the other views' photos. For every
// pixel of `image` (placed on M' by `frame`) where `fillable` is set and a strip
// lies, the colour of the view that resolves it best among those whose page
// mask holds the whole strip triangle. Each view's rendering is first
// moved onto `reference_render` where the two overlap (`reference_valid`;
// the strips' band rows) when SIFT matches agree on an affine map that
// improves their agreement; a view whose detail then still does not
// correlate with the reference's there is not used. With `own_photo` the
// views are the reference's own photo, which needs neither. `photos[v]`
// belongs to `views[v]` (empty: not used). Returns the pixels textured (255).
cv::Mat1b TextureStrips(const std::vector<const ExtensionStrip*>& strips,
                        const std::vector<ViewMask>& views, const std::vector<cv::Mat>& photos,
                        const PixelFrame& frame, bool antialias, const cv::Mat3b& reference_render,
                        const cv::Mat1b& reference_valid, const cv::Mat1b& fillable,
                        cv::Mat3b* image, std::vector<ViewRegistration>* registrations,
                        bool own_photo = false);

}  // namespace docunfold::render
