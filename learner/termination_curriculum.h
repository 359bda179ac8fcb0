// A termination curriculum after ASAP (He et al. 2025): training starts with a loose
// termination distance, so that early policies see long episodes, and the distance moves a small
// step per iteration toward the strict one while the policy keeps up. The signal is the share of
// recently ended episodes that tracked their clip to its end (truncated rather than terminated):
// it is a mean episode length normalized by what each clip allows, so it means the same for a
// 1-second walk and a 30-second dance.
#ifndef MODSKILL_LEARNER_TERMINATION_CURRICULUM_H_
#define MODSKILL_LEARNER_TERMINATION_CURRICULUM_H_

namespace modskill::learner {

class TerminationCurriculum {
 public:
  // Tighten while at least this share of episodes reach their clip's end, loosen below the other.
  static constexpr double kTightenAbove = 0.5;
  static constexpr double kLoosenBelow = 0.25;
  // Each move is this share of (start - end): 40 good iterations go from start to end.
  static constexpr double kStepShare = 0.025;

  // start >= end > 0 (m); start == end is a fixed distance.
  TerminationCurriculum(double start, double end) : start_(start), end_(end), distance_(start) {}

  double distance() const { return distance_; }
  // Restores a saved distance (clamped into [end, start]).
  void set_distance(double distance);
  // After an iteration: `tracked_share` of the recently ended episodes reached their clip's end.
  void Update(double tracked_share);

 private:
  double start_, end_, distance_;
};

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TERMINATION_CURRICULUM_H_
