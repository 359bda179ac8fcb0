// MuJoCo reports warnings (unstable simulation, too many contacts...) through a global hook; left
// alone it writes MUJOCO_LOG.TXT into the process's working directory and prints to stdout. The
// server and tools route them into their log instead, at most one line per distinct message
// every few seconds, with the count of repeats, since a bad clip can warn on every step.
#ifndef MODSKILL_SERVER_CORE_SIM_MUJOCO_WARNINGS_H_
#define MODSKILL_SERVER_CORE_SIM_MUJOCO_WARNINGS_H_

namespace modskill {

// Installs the hook once per process (later calls do nothing). HumanoidModel::Create calls it,
// so every program that simulates has it before its first step.
void RouteMujocoWarningsToLog();

}  // namespace modskill

#endif  // MODSKILL_SERVER_CORE_SIM_MUJOCO_WARNINGS_H_
