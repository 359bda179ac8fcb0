// modskill-learner --family CLIP --param NAME=LO:HI [--param ...]: trains a motor-skill family
// from one clip (learner/family/family_trainer.h) against one server.
#ifndef MODSKILL_LEARNER_TOOLS_FAMILY_COMMAND_H_
#define MODSKILL_LEARNER_TOOLS_FAMILY_COMMAND_H_

#include <atomic>
#include <string>
#include <vector>

namespace modskill::learner {

// Every value of a flag given several times (absl keeps only the last): "--name V" and
// "--name=V", in order.
std::vector<std::string> RepeatedFlagValues(int argc, char** argv, const std::string& name);

// Whether --family was given.
bool FamilyRequested();

// Runs the training; returns the process's exit code (2 for bad flags).
int RunFamilyTraining(const std::string& token, const std::vector<std::string>& params, const std::atomic<bool>& stop);

}  // namespace modskill::learner

#endif  // MODSKILL_LEARNER_TOOLS_FAMILY_COMMAND_H_
