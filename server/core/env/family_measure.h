// What a motor-skill family's rollout did physically (issue 14's bars: a jump's apex and flight
// time, a kick's highest foot), measured frame by frame on the simulated character. The learner's
// FamilyTrainer::Evaluate reads the same measures from observations during training.
#ifndef MODSKILL_SERVER_CORE_ENV_FAMILY_MEASURE_H_
#define MODSKILL_SERVER_CORE_ENV_FAMILY_MEASURE_H_

#include <vector>

#include "server/core/env/humanoid_state.h"
#include "server/core/sim/humanoid_spec.h"

namespace modskill {

struct FamilyMotionMeasures {
  double apex_height = 0;       // m, the root's highest
  double highest_effector = 0;  // m, the highest an ankle, toe, wrist or hand got
  double flight_s = 0;          // s with every foot above its first-frame height + 3 cm
};

class FamilyMotionMeter {
 public:
  FamilyMotionMeter(const HumanoidSpec& spec, double control_dt);

  // One simulated frame, the episode's first included (it sets each foot's ground height).
  void Observe(const HumanoidState& sim);
  const FamilyMotionMeasures& measures() const { return measures_; }

 private:
  std::vector<int> feet_, effectors_;
  std::vector<double> foot_ground_;  // per foot: first-frame height + 3 cm
  double control_dt_;
  bool first_ = true;
  FamilyMotionMeasures measures_;
};

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_ENV_FAMILY_MEASURE_H_
