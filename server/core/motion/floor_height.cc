#include "server/core/motion/floor_height.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

namespace modskill {
namespace {

int HalfWidthInFrames(double seconds, double fps) {
  return std::max(0, static_cast<int>(std::lround(seconds * fps)));
}

// Each helper costs O(frames) or O(frames x kMaxQuantileSamples), whatever the frame rate: an
// import at --fps 10000 has windows of thousands of frames.
constexpr int kMaxQuantileSamples = 64;

std::vector<double> MovingAverage(const std::vector<double>& values, int half) {
  const int frames = static_cast<int>(values.size());
  std::vector<double> prefix(frames + 1, 0.0), out(frames);
  for (int f = 0; f < frames; ++f) prefix[f + 1] = prefix[f] + values[f];
  for (int f = 0; f < frames; ++f) {
    const int first = std::max(0, f - half), last = std::min(frames - 1, f + half);
    out[f] = (prefix[last + 1] - prefix[first]) / (last - first + 1);
  }
  return out;
}

// The maximum over each frame's window, with a deque of candidates (indices of decreasing values).
std::vector<double> RollingMax(const std::vector<double>& values, int half) {
  const int frames = static_cast<int>(values.size());
  std::vector<double> out(frames);
  std::deque<int> candidates;
  int next = 0;
  for (int f = 0; f < frames; ++f) {
    for (; next < frames && next <= f + half; ++next) {
      while (!candidates.empty() && values[candidates.back()] <= values[next]) candidates.pop_back();
      candidates.push_back(next);
    }
    while (candidates.front() < f - half) candidates.pop_front();
    out[f] = values[candidates.front()];
  }
  return out;
}

// A long window is read at a stride: at most kMaxQuantileSamples values per frame.
std::vector<double> RollingQuantile(const std::vector<double>& values, int half, double quantile) {
  const int frames = static_cast<int>(values.size());
  const int stride = std::max(1, (2 * half + 1 + kMaxQuantileSamples - 1) / kMaxQuantileSamples);
  std::vector<double> out(frames), window;
  for (int f = 0; f < frames; ++f) {
    window.clear();
    for (int g = std::max(0, f - half); g <= std::min(frames - 1, f + half); g += stride) window.push_back(values[g]);
    const size_t k = static_cast<size_t>(quantile * static_cast<double>(window.size() - 1));
    std::nth_element(window.begin(), window.begin() + k, window.end());
    out[f] = window[k];
  }
  return out;
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

std::vector<double> PinFloorToStance(const std::vector<double>& floor, const std::vector<double>& lowest,
                                     const std::vector<bool>& stance) {
  const int frames = static_cast<int>(floor.size());
  std::vector<int> anchors;
  for (int f = 0; f < frames; ++f) {
    if (stance[f]) anchors.push_back(f);
  }
  if (anchors.empty()) return floor;
  std::vector<double> pinned(frames);
  size_t next = 0;  // the first anchor at or after f
  for (int f = 0; f < frames; ++f) {
    while (next < anchors.size() && anchors[next] < f) ++next;
    const int after = anchors[std::min(next, anchors.size() - 1)];
    const int before = next > 0 ? anchors[next - 1] : after;
    const double offset_before = lowest[before] - floor[before], offset_after = lowest[after] - floor[after];
    // Between two anchors the offset runs linearly; before the first and after the last it holds.
    double offset = offset_after;
    if (before < f && f < after) {
      offset = offset_before + (offset_after - offset_before) * (f - before) / static_cast<double>(after - before);
    }
    pinned[f] = std::min(floor[f] + offset, lowest[f]);
  }
  return pinned;
}

}  // namespace modskill
