# modskill_learner_family: the algorithm core of a motor-skill family from one clip (Lee et al.
# 2021, issue 14): variable time-step GAE, the fitness, the elite set and its k-d tree, the
# elites' bootstrap, the parameterization network and the parameter curriculum.
add_library(modskill_learner_family STATIC
  ${CMAKE_CURRENT_LIST_DIR}/variable_step_gae.cc
  ${CMAKE_CURRENT_LIST_DIR}/kd_tree.cc
  ${CMAKE_CURRENT_LIST_DIR}/elite_set.cc
  ${CMAKE_CURRENT_LIST_DIR}/elite_bootstrap.cc
  ${CMAKE_CURRENT_LIST_DIR}/parameterization_net.cc
  ${CMAKE_CURRENT_LIST_DIR}/parameter_density.cc
  ${CMAKE_CURRENT_LIST_DIR}/parameter_curriculum.cc)
target_include_directories(modskill_learner_family PUBLIC ${CMAKE_SOURCE_DIR})
target_link_libraries(modskill_learner_family PUBLIC modskill_family_parameters ${TORCH_LIBRARIES} absl::status
  absl::statusor absl::strings absl::span)
target_compile_options(modskill_learner_family PRIVATE ${TORCH_CXX_FLAGS} -Wall -Wextra -Wno-unused-parameter)
target_precompile_headers(modskill_learner_family PRIVATE <torch/torch.h>)

# modskill_learner_family_trainer: a family trained against a server's family session: its policy
# and critic, the coverage of its elites, and the trainer (modskill-learner --family).
add_library(modskill_learner_family_trainer STATIC
  ${CMAKE_CURRENT_LIST_DIR}/family_policy.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_coverage.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_session.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_trainer.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_trainer_collect.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_trainer_update.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_trainer_checkpoint.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_trainer_evaluate.cc
  ${CMAKE_CURRENT_LIST_DIR}/family_export.cc)
target_link_libraries(modskill_learner_family_trainer PUBLIC modskill_learner_family modskill_learner_algo
  modskill_learner_nn modskill_client)
target_compile_options(modskill_learner_family_trainer PRIVATE ${TORCH_CXX_FLAGS} -Wall -Wextra -Wno-unused-parameter)
modskill_torch_pch(modskill_learner_family_trainer)
