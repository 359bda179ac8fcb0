// modskill-policy-average: the weight average of several policy.pt files of one run (e.g. its
// last milestone exports, --milestones), written as one policy.pt that runs like any other.
//
//   modskill-policy-average --out OUT.pt IN1.pt IN2.pt [IN3.pt ...]
#include <cstdio>
#include <string>
#include <vector>

#include "absl/flags/flag.h"
#include "absl/flags/parse.h"
#include "absl/flags/usage.h"
#include "learner/policy_average.h"

ABSL_FLAG(std::string, out, "", "the averaged policy.pt to write");

int main(int argc, char** argv) {
  absl::SetProgramUsageMessage("modskill-policy-average --out OUT.pt IN1.pt IN2.pt [IN3.pt ...]");
  std::vector<char*> args = absl::ParseCommandLine(argc, argv);
  const std::string out = absl::GetFlag(FLAGS_out);
  if (out.empty() || args.size() < 3) {
    std::fprintf(stderr, "usage: modskill-policy-average --out OUT.pt IN1.pt IN2.pt [IN3.pt ...]\n");
    return 2;
  }
  const std::vector<std::string> inputs(args.begin() + 1, args.end());
  if (absl::Status status = modskill::learner::AveragePolicies(inputs, out); !status.ok()) {
    std::fprintf(stderr, "error: %s\n", std::string(status.message()).c_str());
    return 1;
  }
  std::printf("%s: the mean of %zu policies\n", out.c_str(), inputs.size());
  return 0;
}
