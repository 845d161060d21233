// Image-quality metrics between a reference and a test image of the same
// size: PSNR, SSIM, MS-SSIM and FLIP (LDR).
//
// Inputs are 8-bit sRGB images (Image::PixelType::kU8) with 1 to 4 channels:
// gray (1, 2 channels) counts as R = G = B; CompareImages ignores alpha
// (channel 2 or 4), so every metric uses all pixels; CompareCovered (at the
// end) measures only pixels covered in both frames and reports coverage apart. Sizes must match (Status::Invalid
// otherwise); x = column, y = row as in image.h.
//
// Definitions (docs/metrics.md has the reference values they reproduce):
//  - PSNR: 10 log10(255^2 / MSE), MSE over all pixels and the three channels
//    R, G, B. Identical images give +infinity.
//  - SSIM: Wang, Bovik, Sheikh, Simoncelli 2004, "Image quality assessment:
//    from error visibility to structural similarity", IEEE TIP 13(4).
//    11x11 Gaussian window of sigma 1.5 (normalized to sum 1), K1 = 0.01,
//    K2 = 0.03, L = 255, population (not sample) covariances, computed in
//    double, averaged over the valid region: the (W-10) x (H-10) positions
//    where the whole window lies inside the image. This is scikit-image's
//    structural_similarity(gaussian_weights=True, sigma=1.5,
//    use_sample_covariance=False, data_range=255) cropped the same way.
//    Two variants: on luma Y = 0.299 R + 0.587 G + 0.114 B (in double, not
//    rounded) and the mean of the SSIMs of R, G and B.
//  - MS-SSIM: Wang, Simoncelli, Bovik 2003, "Multi-scale structural
//    similarity for image quality assessment", on luma. Five scales with
//    weights 0.0448, 0.2856, 0.3001, 0.2363, 0.1333; between scales a 2x2
//    box average (an odd last row / column is dropped). Scales 1-4
//    contribute the valid-region mean of the contrast-structure term cs,
//    scale 5 the valid-region mean SSIM (luminance x cs):
//      MS-SSIM = prod_{j=1..4} mean(cs_j)^w_j * mean(ssim_5)^w_5.
//    A negative term (anti-correlated or unrelated structure at a scale)
//    would make the fractional power undefined; such a term counts as 0, so
//    MS-SSIM is 0, as TensorFlow's ssim_multiscale does (it applies a ReLU).
//    Needs the coarsest scale to hold a window: both sides >= 11 * 16 = 176
//    pixels.
//  - FLIP: Andersson, Nilsson, Akenine-Moeller, Oskarsson, Astrom, Fairchild
//    2020, "FLIP: A Difference Evaluator for Alternating Images", HPG, in its
//    LDR form as NVIDIA's reference implementation v1.6 computes it (spatial
//    CSF filtering in YCxCz, Hunt-adjusted HyAB color difference, edge and
//    point feature difference; single-precision per-pixel arithmetic, edges
//    clamped). The mean is summed in double.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <vector>

#include "base/status.h"
#include "stages/geometry/core/image.h"

namespace pb {

// FLIP's default observer: 0.7 m from a 0.7 m wide, 3840-pixel monitor,
// 0.7 * 3840 / 0.7 * pi / 180 pixels per degree evaluated in float as the
// reference implementation does (67.02064514160156).
double FlipDefaultPpd();

struct SsimResult {
  double luma = 0;  // on Y = 0.299 R + 0.587 G + 0.114 B
  double rgb = 0;   // mean of the SSIMs of R, G, B
};

// Status::Invalid: size mismatch, not 8-bit, or a side below 11 pixels.
Expected<double> Psnr(const Image& reference, const Image& test);
Expected<SsimResult> Ssim(const Image& reference, const Image& test);
// Status::Invalid also when a side is below 176 pixels.
Expected<double> MsSsim(const Image& reference, const Image& test);

struct FlipResult {
  int width = 0;
  int height = 0;
  std::vector<float> error;  // width * height per-pixel FLIP values in [0,1], row-major
  double mean = 0;           // mean of `error`, summed in double
};
// `ppd`: pixels per degree of visual angle (> 0).
Expected<FlipResult> Flip(const Image& reference, const Image& test, double ppd = FlipDefaultPpd());

// The FLIP error map as an 8-bit RGB image through the "magma" colormap
// (matplotlib's, by Smith and van der Walt, CC0; the map FLIP's tool uses):
// value v picks entry round(255 v), as the FLIP tool does.
Image FlipErrorColorMap(const FlipResult& flip);
// Entry `index` (0..255) of that colormap as 8-bit sRGB (for legends).
std::array<uint8_t, 3> MagmaColor(int index);

struct ImageMetricsOptions {
  double flip_ppd = FlipDefaultPpd();
  // CompareCovered with depth maps: surfaces whose depths differ by more
  // than this fraction of the reference's depth are different surfaces.
  double depth_tolerance = 0.05;
};

// All four metrics. For images too small for SSIM (< 11 px) or MS-SSIM
// (< 176 px) those values are NaN instead of an error, so small images still
// get PSNR and FLIP.
struct ImageMetrics {
  double psnr_db = 0;  // +infinity for identical images
  double ssim_luma = 0;
  double ssim_rgb = 0;
  double ms_ssim_luma = 0;
  double flip_mean = 0;
};
// `flip` (optional) receives the FLIP error map.
Expected<ImageMetrics> CompareImages(const Image& reference, const Image& test,
                                     const ImageMetricsOptions& options = {},
                                     FlipResult* flip = nullptr);

// The image with every pixel whose alpha is 0 (where nothing was drawn) made
// black, alpha kept; an image without alpha (1 or 3 channels) is returned
// as it is. Whole-frame metrics of frames drawn on different backgrounds
// (render.frames / render.splats `background`) compare them so, as both drawn
// on the renderers' default black. Edge pixels, covered by some of their
// supersamples, keep the blend with the background they were drawn on.
Image BackgroundToBlack(Image image);

// The color of the image's pixels with alpha 0 (the background it was drawn
// on) when they all share one; nullopt when the image has no alpha, no such
// pixel, or several colors there.
std::optional<std::array<uint8_t, 3>> DrawnBackground(const Image& image);

// ---- Covered pixels ----
//
// Frames of a surface against frames of another (a workflow's model against
// the scan's splats, or against HPM) differ in where there is surface at all
// (silhouettes, holes, surface one side invented) and in what the surface
// looks like. Whole-frame metrics mix the two, and the first dominates. Here
// they are apart. A pixel is covered when its alpha is > 0 (render.frames and
// render.splats write 255 where geometry is, 0 on background; an image without
// alpha is covered everywhere).
//  - Coverage agreement: IoU = |covered in both| / |covered in either|.
//  - Hole pixels: pixels of the reference's footprint where the test frame
//    shows background, whether at the silhouette or inside it;
//    `enclosed_hole_px` counts those of them that no 4-connected path of the
//    test frame's background links to the frame's border: background seen
//    through the surface inside its own silhouette (a hole in a wall);
//    `silhouette_hole_px` those of the others that touch (8-neighbourhood) a
//    pixel the test frame covers: its outline falls about a pixel short of
//    the reference's footprint there, as a low-poly chord across a curved
//    silhouette does (a shortfall of the outline rather than missing
//    surface; the rest, open holes deeper than a pixel, are missing parts).
//    hole_fraction = hole_px / footprint_px. The footprint is the reference's
//    sample mask when one is given (render.splats: the pixels into which a
//    visible scan point's center projects, the scan's evidence), else its
//    covered pixels. A splat reference covers more than its samples: each
//    disk a local spacing around its point, and where the spacing is
//    inflated (a sparse border, an isolated sample) a disk of up to several
//    pixels past anything the scanner saw; a model that ends at the last
//    sample is right there, and a person sees no hole. `splat_hole_px` /
//    `splat_hole_fraction` keep the count against all the reference's covered
//    pixels (the disks), the definition before sample masks.
//  - Appearance, on the compared pixels: covered in both frames, and so are
//    their 4 neighbours (edge pixels blend the surface with the background
//    under supersampling, so they belong to the silhouette, not the texture).
//    PSNR is the MSE over the compared pixels. For SSIM, MS-SSIM and FLIP, the
//    test frame first takes the reference's pixels everywhere outside the
//    compared pixels (both frames are then identical there), the maps are
//    computed on the full frames as above, and averaged over the compared
//    pixels only (SSIM: the windows centered on one; MS-SSIM: at each coarser
//    scale a pixel is compared when any of its 2x2 parents was). So a window
//    that straddles the mask's edge sees only the differences inside it.
//    No compared pixel (or too small a frame, as CompareImages): NaN.
//  - With depth maps of both frames (frames.h: view depth per pixel, 0 where
//    nothing was hit): of the pixels covered in both, those where the tested
//    surface is nearer than the reference's by more than depth_tolerance x
//    the reference's depth (`nearer_px`: surface the model invented in front
//    of what the reference shows, e.g. Poisson closing an open side), or
//    farther (`farther_px`: the model misses the reference's surface there and
//    shows what is behind it) are counted apart and left out of the compared
//    pixels (with their 4 neighbours): they are geometry, not texture.
struct CoverageStats {
  size_t reference_px = 0;  // covered in the reference
  size_t test_px = 0;       // covered in the test frame
  size_t both_px = 0;
  size_t union_px = 0;
  double iou = 1;           // both / union; 1 when neither has coverage
  bool sample_mask = false;  // holes were counted on the reference's sample mask
  size_t footprint_px = 0;   // the reference's sample pixels (sample_mask), else reference_px
  size_t hole_px = 0;        // footprint pixels where the test frame is background
  size_t enclosed_hole_px = 0;  // of hole_px, inside the test frame's silhouette
  size_t silhouette_hole_px = 0;  // of hole_px, not enclosed, touching a pixel the test frame covers
  double hole_fraction = 0;     // hole_px / footprint_px (0 without footprint)
  size_t splat_hole_px = 0;     // reference covered, test background
  double splat_hole_fraction = 0;  // splat_hole_px / reference_px (0 without reference coverage)
  size_t compared_px = 0;       // the pixels the metrics below are measured on
  bool depth_checked = false;   // both depth maps were given
  size_t nearer_px = 0;         // covered in both, tested surface nearer (depth_checked)
  size_t farther_px = 0;        // covered in both, tested surface farther (depth_checked)
};

struct CoveredComparison {
  CoverageStats coverage;
  ImageMetrics metrics;  // PSNR, SSIM, MS-SSIM, FLIP on the compared pixels
};

// `flip` (optional) receives the FLIP map of the filled frames (differences
// inside the compared pixels spread a few pixels past them through FLIP's
// filters; elsewhere it is 0). Status::Invalid as
// CompareImages.
// `reference_depth` and `test_depth` (both or neither): one-channel kF32
// depth maps of the frames' size (Status::Invalid otherwise).
// `reference_samples` (optional): the reference's sample mask, one kU8
// channel of the frames' size, > 0 on sample pixels (Status::Invalid
// otherwise); hole pixels are counted on it.
// `map` (optional) receives the coverage map: an 8-bit RGB picture of the
// frames' size with one colour per class of pixel (the kCoverageMap*
// colours below), so a person sees where the figures come from.
Expected<CoveredComparison> CompareCovered(const Image& reference, const Image& test,
                                           const ImageMetricsOptions& options = {},
                                           FlipResult* flip = nullptr, const Image* reference_depth = nullptr,
                                           const Image* test_depth = nullptr,
                                           const Image* reference_samples = nullptr, Image* map = nullptr);

// The coverage map's classes, in the order a reader that must merge pixels
// (a thumbnail) keeps them, most telling first. A pixel covered in both
// frames and not in front or behind shows the test frame's luma as a gray
// in [96, 224] (the model, for orientation); the other classes have fixed
// colours.
inline constexpr std::array<uint8_t, 3> kCoverageMapHoleEnclosed = {255, 230, 0};  // a hole the test frame encloses
inline constexpr std::array<uint8_t, 3> kCoverageMapHoleOpen = {255, 128, 0};      // open, deeper than a pixel
inline constexpr std::array<uint8_t, 3> kCoverageMapHoleOutline = {255, 0, 0};     // at the test's outline
inline constexpr std::array<uint8_t, 3> kCoverageMapNearer = {255, 0, 255};   // the test's surface in front
inline constexpr std::array<uint8_t, 3> kCoverageMapFarther = {0, 200, 255};  // the test's surface behind
inline constexpr std::array<uint8_t, 3> kCoverageMapTestOnly = {40, 90, 255};  // the test covers, the reference not
inline constexpr std::array<uint8_t, 3> kCoverageMapReferenceOnly = {64, 64, 64};  // reference, not a footprint pixel
inline constexpr std::array<uint8_t, 3> kCoverageMapNeither = {0, 0, 0};
// The fixed colours from most to least telling: the defects (the holes, the
// surface in front, behind), then model only and disks only. The report's
// thumbnails keep a defect wherever one falls in a box, and else show what
// most of the box is (cli/report/report_images.cc, RankedDownscale).
inline constexpr std::array<std::array<uint8_t, 3>, 7> kCoverageMapRanked = {
    kCoverageMapHoleEnclosed, kCoverageMapHoleOpen, kCoverageMapHoleOutline, kCoverageMapNearer,
    kCoverageMapFarther,      kCoverageMapTestOnly, kCoverageMapReferenceOnly};

}  // namespace pb
