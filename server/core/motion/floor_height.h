// The floor under a clip, frame by frame. A retargeted or captured clip does not keep its
// contacts on one level: a skeleton whose limbs differ in proportion from the actor's, or a take
// whose floor is not level, leaves whole stretches floating. Measured on the shipped library
// before this existed: DeepMimic's stealthy walk 8-12 cm above z = 0 for most of its 4 s, its
// crawl 5-12 cm, CMU 02_01 rising from 0 to 6 cm over its 2.8 s. A simulated character cannot
// float, so such a reference asks for what no policy can do.
//
// The floor of frame f is a low quantile of the per-frame lowest geometry points within
// +-window of f, then a moving average: a flight shorter than the window keeps its height above
// the contacts around it, a few glitched frames below the rest are outvoted, and the shift
// changes slowly enough to add no jerk.
#ifndef MODSKILL_SERVER_CORE_MOTION_FLOOR_HEIGHT_H_
#define MODSKILL_SERVER_CORE_MOTION_FLOOR_HEIGHT_H_

#include <vector>

namespace modskill {

struct FloorHeightOptions {
  double window_seconds = 0.5;     // half-width of the window the quantile is taken over
  double quantile = 0.1;           // of the lowest points in the window
  double smoothing_seconds = 0.2;  // half-width of the moving average over the quantiles
  int passes = 3;                  // each over what the passes before left (a slope's lag)
};

// `lowest[f]`: the lowest geometry point of frame f (m). Returns the floor height of each frame:
// never above that frame's lowest point, and equal to it at the clip's lowest frame.
std::vector<double> FloorHeights(const std::vector<double>& lowest, double fps,
                                 const FloorHeightOptions& options = {});

// The floor pinned to the supporting foot. Where `stance[f]` (a foot carries the body in frame
// f), the floor is that frame's lowest point: FloorHeights' quantile leaves a retargeted walk's
// stance foot up to ~2.6 cm above it between the frames it averages. Between stance frames the
// offset from `floor` runs linearly (a flight keeps its height above the contacts at its ends);
// before the first and after the last it holds. Never above a frame's lowest point.
std::vector<double> PinFloorToStance(const std::vector<double>& floor, const std::vector<double>& lowest,
                                     const std::vector<bool>& stance);

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_MOTION_FLOOR_HEIGHT_H_
