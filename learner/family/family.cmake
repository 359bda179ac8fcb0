# modskill_learner_family: the algorithm core of a motor-skill family from one clip (Lee et al.
# 2021, issue 14): variable time-step GAE, the fitness, the elite set and its k-d tree, the
# elites' bootstrap, the parameterization network and the parameter curriculum.
add_library(modskill_learner_family STATIC
  ${CMAKE_CURRENT_LIST_DIR}/variable_step_gae.cc
  ${CMAKE_CURRENT_LIST_DIR}/fitness.cc
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
