# The learning algorithms that do not depend on a network: GAE, PPO's loss, its KL-steered and its
# decayed learning rate, AMP's discriminator loss and reward, the termination curriculum, and the training
# logs (TensorBoard event files, CSV).
add_library(modskill_learner_algo STATIC
  ${CMAKE_CURRENT_LIST_DIR}/amp_loss.cc
  ${CMAKE_CURRENT_LIST_DIR}/gae.cc
  ${CMAKE_CURRENT_LIST_DIR}/kl_adaptive_learning_rate.cc
  ${CMAKE_CURRENT_LIST_DIR}/learning_rate_decay.cc
  ${CMAKE_CURRENT_LIST_DIR}/ppo_loss.cc
  ${CMAKE_CURRENT_LIST_DIR}/tensorboard_writer.cc
  ${CMAKE_CURRENT_LIST_DIR}/termination_curriculum.cc)
target_include_directories(modskill_learner_algo PUBLIC ${CMAKE_SOURCE_DIR})
target_link_libraries(modskill_learner_algo PUBLIC modskill_common modskill_tensorboard_proto
  ${TORCH_LIBRARIES} absl::status absl::statusor absl::strings absl::str_format)
target_compile_options(modskill_learner_algo PRIVATE ${TORCH_CXX_FLAGS} -Wall -Wextra -Wno-unused-parameter)
modskill_torch_pch(modskill_learner_algo)
