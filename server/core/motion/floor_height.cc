#include "server/core/motion/floor_height.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace modskill {
namespace {

int HalfWidthInFrames(double seconds, double fps) {
  return std::max(0, static_cast<int>(std::lround(seconds * fps)));
}

// Applies `reduce(first, last)` over each frame's window [f - half, f + half], clipped to the clip.
template <typename Reduce>
std::vector<double> OverWindows(const std::vector<double>& values, int half, Reduce reduce) {
  const int frames = static_cast<int>(values.size());
  std::vector<double> out(frames);
  for (int f = 0; f < frames; ++f) {
    out[f] = reduce(values.begin() + std::max(0, f - half), values.begin() + std::min(frames - 1, f + half) + 1);
  }
  return out;
}

std::vector<double> MovingAverage(const std::vector<double>& values, int half) {
  return OverWindows(values, half, [](auto first, auto last) {
    double sum = 0;
    for (auto it = first; it != last; ++it) sum += *it;
    return sum / static_cast<double>(last - first);
  });
}

std::vector<double> RollingMax(const std::vector<double>& values, int half) {
  return OverWindows(values, half, [](auto first, auto last) { return *std::max_element(first, last); });
}

std::vector<double> RollingQuantile(const std::vector<double>& values, int half, double quantile) {
  std::vector<double> window;
  return OverWindows(values, half, [&](auto first, auto last) {
    window.assign(first, last);
    const size_t k = static_cast<size_t>(quantile * static_cast<double>(window.size() - 1));
    std::nth_element(window.begin(), window.begin() + k, window.end());
    return window[k];
  });
}

}  // namespace

std::vector<double> FloorHeights(const std::vector<double>& lowest, double fps, const FloorHeightOptions& options) {
  const int window = HalfWidthInFrames(options.window_seconds, fps);
  const int smoothing = HalfWidthInFrames(options.smoothing_seconds, fps);
  // A quantile over a window lags a slope (on a rising floor it reads the window's early part);
  // each pass takes it again over what the floor so far leaves, which on a slope is about
  // constant and on a flight still reads the contacts around it.
  std::vector<double> floor(lowest.size(), 0.0), left = lowest;
  for (int pass = 0; pass < options.passes; ++pass) {
    const std::vector<double> more = MovingAverage(RollingQuantile(left, window, options.quantile), smoothing);
    for (size_t f = 0; f < lowest.size(); ++f) {
      floor[f] += more[f];
      left[f] = lowest[f] - floor[f];
    }
  }
  // No frame may end up in the ground. Where the floor is above a frame's lowest point, it comes
  // down by a smoothed rolling maximum of that excess: the average over f's window of maxima
  // that each include f is at least f's own excess, so every frame clears, without a step.
  std::vector<double> excess(lowest.size());
  for (size_t f = 0; f < lowest.size(); ++f) excess[f] = std::max(0.0, floor[f] - lowest[f]);
  const std::vector<double> lowering = MovingAverage(RollingMax(excess, smoothing), smoothing);
  double clearance = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < lowest.size(); ++f) {
    floor[f] -= lowering[f];
    clearance = std::min(clearance, lowest[f] - floor[f]);
  }
  // ... and the lowest frame of the clip touches it (the lowering may leave every frame clear).
  for (size_t f = 0; f < lowest.size(); ++f) floor[f] = std::min(floor[f] + clearance, lowest[f]);
  return floor;
}

}  // namespace modskill
