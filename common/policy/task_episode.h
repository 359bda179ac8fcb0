// How long a task episode may last (steer, reach, strike): a wire contract the server's task
// envs and the learner's normalized return share (modskill.proto, SessionConfig.task).
#ifndef MODSKILL_COMMON_POLICY_TASK_EPISODE_H_
#define MODSKILL_COMMON_POLICY_TASK_EPISODE_H_

namespace modskill {

// Steps a task episode lasts at most when the session leaves max_episode_steps at 0 (10 s at
// 30 Hz).
inline constexpr int kDefaultTaskEpisodeSteps = 300;

// A task session's step limit: its max_episode_steps, or the default for 0.
inline int TaskEpisodeSteps(int max_episode_steps) {
  return max_episode_steps > 0 ? max_episode_steps : kDefaultTaskEpisodeSteps;
}

}  // namespace modskill

#endif  // MODSKILL_COMMON_POLICY_TASK_EPISODE_H_
