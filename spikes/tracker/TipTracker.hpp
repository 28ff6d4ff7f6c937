#pragma once
// The tip tracker: finds the spike tips of a spiky mesh and matches them across frames,
// to measure how coherent the spikes are in motion (tests, the benchmark report, and
// `ferro-tips` on a shot's frames).
//
// It is a measuring tool, independent of how ferro-spikes made the tips: a tip is a vertex
// of the spiky mesh that stands out of the frame's undisplaced surface mesh (the
// ferro-surface output the spikes were added to) by at least `minHeight` and is the highest
// vertex of its one-ring; of two such maxima closer than half the frame's median tip
// spacing only the higher is kept. Height = distance from the nearest surface vertex's
// tangent plane, so flat, undisplaced fluid has height ~0 at any surface resolution.
#include "sim/core/TriangleMesh.hpp"

#include <string>
#include <vector>

namespace ferro {

struct SpikeTipSample {
    Vec3d position;     ///< the tip vertex [m]
    double height = 0;  ///< height above the undisplaced surface [m]
    Vec3d normal{0, 0, 1};                 ///< the undisplaced surface's unit normal under the tip
    Vec3d surfaceVelocity = Vec3d::Zero(); ///< the undisplaced surface's velocity under the tip [m/s]
    bool hasVelocity = false;              ///< the surface mesh had vertex velocities
    /// The spike's foot [m]: where its axis meets the undisplaced surface. The axis runs from
    /// the apex through the centroid of the spike's volume (the mesh reached downhill from the
    /// apex down to 5 % of its height and within 0.75 median tip spacings, as columns over
    /// the surface), so a leaning spike's foot is not under its apex. A
    /// tip carried by the flow is its foot moving; a leaning spike that sinks or straightens
    /// moves its apex over a still foot.
    Vec3d base = Vec3d::Zero();
    bool hasBase = false;                  ///< base was found (else the flow uses the apex)
};

struct TipFinderParams {
    double minHeight = 2e-4;   ///< a tip stands at least this far out of the surface [m], > 0
};

/// The tips of `spiky` (a ferro-spikes output) over `surface` (its input). Empty when either
/// mesh is empty. Sorted by decreasing height.
std::vector<SpikeTipSample> findTips(const TriangleMesh& spiky, const TriangleMesh& surface,
                                     const TipFinderParams& params = {});

/// Median distance from each tip to its nearest other tip [m]; 0 with fewer than two tips.
double medianTipSpacing(const std::vector<SpikeTipSample>& tips);

/// How the tips of one frame (a) became the tips of the next (b).
struct TipFrameMatch {
    int tipsA = 0, tipsB = 0;
    int matched = 0;            ///< pairs matched one to one within the gate
    int died = 0, born = 0;     ///< tips of a without a match, of b without a match
    /// Of those, the ones at least `edgeFraction` of the frame's largest tip tall: a tip that
    /// appears or vanishes inside the spiky region (not at its fading edge).
    int interiorDied = 0, interiorBorn = 0;
    double spacing = 0;         ///< tip spacing l: median nearest-tip distance of a (else b) [m]
    double medianMove = 0;      ///< median distance a matched tip moved [m]
    double maxMove = 0;         ///< largest distance a matched tip moved [m]
    /// Matched tips that moved less than 0.1 l, over max(tipsA, tipsB) (1 when both are empty).
    double stableFraction = 1;
    /// The same over the interior tips only (at least `edgeFraction` of the largest tip tall in
    /// either frame): the share of them matched and moved less than 0.1 l.
    double interiorStableFraction = 1;
    /// Largest height change of a tip between the frames over the larger of the two frames'
    /// largest tips: matched tips by their difference, born and died tips by their whole
    /// height (a tip that appears 3 mm tall jumped 3 mm).
    double maxHeightJump = 0;
    double largestTip = 0;      ///< the larger of the two frames' largest tip heights [m]
    /// Largest distance of a matched tip of b from where the motion of its matched neighbours
    /// predicted it [m] (the raw move when matching without prediction).
    double maxResidual = 0;
    /// Do the tips move with the fluid under them? Over the matched interior tips of both
    /// frames' surfaces with velocities, along the surface (the mean of the two normals):
    /// a tip's velocity v = its foot's move (SpikeTipSample::base; the apex's where a frame
    /// has none) / the frame interval, the fluid's u = the mean of the surface velocity under
    /// it in the two frames. 0 when there is no interval or velocity.
    int flowTips = 0;            ///< the tips compared
    double surfaceSpeed = 0;     ///< mean |u| [m/s]
    double tipSpeed = 0;         ///< mean |v| [m/s]
    double flowDifference = 0;   ///< mean |v - u| [m/s] (sum it over steps, not the ratio below)
    double flowMismatch = 0;     ///< sum |v - u| / sum |u| (0 = the tips ride the flow exactly;
                                 ///< +inf when tips move on a surface that does not)
};

/// Matches b's tips to a's: pairs in order of increasing distance, each tip used once, only
/// pairs closer than `gate` x l (l = the spacing of a, else of b).
///
/// With `predict`, the distance is taken from where a's tip is expected in b: the pattern
/// contracts as the field grows (l = alpha / |H|, a few % a frame on an approaching magnet)
/// and slides with a moving magnet, so tips ten rings out move more than half a spacing in one
/// frame while moving continuously; matched without prediction they counted as a death and a
/// birth at full height. The prediction is a local similarity (isotropic scale and shift,
/// least squares) of the motion of the tip's kMotionNeighbours nearest matched tips. It starts
/// from the tips that moved less than a quarter spacing (there the nearest tip is surely the
/// same one) and grows outward round by round, keeping matches within a quarter spacing of
/// the prediction, until no tip is added; then every tip is matched from its prediction
/// within the gate. A tip that really appears, vanishes or jumps against its neighbours
/// still falls outside the gate. Moves (and the 0.1 l stability) stay the raw distances a
/// tip travelled.
/// With `interval` > 0 [s] (frame b's time minus a's), also the flow statistics above.
TipFrameMatch matchTips(const std::vector<SpikeTipSample>& a, const std::vector<SpikeTipSample>& b,
                        double gate = 0.5, double edgeFraction = 0.25, bool predict = true, double interval = 0);

/// A shot's tips over a frame range: the tips of every frame and the match of each frame to
/// the next.
struct TipTrack {
    int first = 0;                                   ///< first frame
    std::vector<std::vector<SpikeTipSample>> tips;   ///< per frame, first..last
    std::vector<TipFrameMatch> steps;                ///< steps[k]: frame first+k -> first+k+1
};

/// Reads frames first..last of the spiky-mesh and surface-mesh patterns ({:04} / %04d
/// placeholders, as every stage takes them) and tracks their tips. Throws MeshFileError
/// (missing 4 / malformed 2) at the first frame that cannot be read.
TipTrack trackTips(const std::string& spikyPattern, const std::string& surfacePattern, int first, int last,
                   const TipFinderParams& params = {}, double gate = 0.5, double edgeFraction = 0.25,
                   bool predict = true);

/// The track as CSV: one row per step (frame, tips, matched, born, died, interior_born,
/// interior_died, spacing_mm, median_move_mm, max_move_mm, stable_fraction, interior_stable_fraction,
/// max_height_jump, largest_tip_mm, max_residual_mm, flow_tips, surface_speed_mm_s,
/// tip_speed_mm_s, flow_difference_mm_s, flow_mismatch). The frame interval comes from the meshes' `time` headers.
std::string tipTrackCsv(const TipTrack& track);

} // namespace ferro
