#include "learner/termination_curriculum.h"

#include <algorithm>

namespace modskill::learner {

void TerminationCurriculum::set_distance(double distance) { distance_ = std::clamp(distance, end_, start_); }

void TerminationCurriculum::Update(double tracked_share) {
  const double step = kStepShare * (start_ - end_);
  if (tracked_share >= kTightenAbove) {
    distance_ = std::max(end_, distance_ - step);
  } else if (tracked_share < kLoosenBelow) {
    distance_ = std::min(start_, distance_ + step);
  }
}

}  // namespace modskill::learner
