#include "nn/schedulers/scheduler.h"

#include "core/error.h"
#include "nn/schedulers/scheduler_ddim.h"
#include "nn/schedulers/scheduler_euler.h"
#include "nn/schedulers/scheduler_euler_ancestral.h"

namespace u3d::nn {

torch::Tensor Scheduler::timestep(int step_index) const {
  check_step_index(step_index);
  return timesteps_[step_index];
}

void Scheduler::check_step_index(int step_index) const {
  require(timesteps_.defined(), name() + ": set_timesteps was not called");
  require(step_index >= 0 && step_index < num_steps(), name() + ": step index " + std::to_string(step_index) +
                                                            " outside the schedule of " +
                                                            std::to_string(num_steps()) + " steps");
}

std::optional<SchedulerKind> scheduler_kind_from_class_name(const std::string& class_name) {
  if (class_name == "EulerAncestralDiscreteScheduler") return SchedulerKind::EulerAncestral;
  if (class_name == "EulerDiscreteScheduler") return SchedulerKind::Euler;
  if (class_name == "DDIMScheduler") return SchedulerKind::Ddim;
  return std::nullopt;
}

std::unique_ptr<Scheduler> make_scheduler(const SchedulerConfig& config, std::optional<SchedulerKind> kind) {
  if (!kind) kind = scheduler_kind_from_class_name(config.class_name);
  require(kind.has_value(), config.source + ": scheduler class '" + config.class_name +
                                "' is not implemented (supported: EulerAncestralDiscreteScheduler, "
                                "EulerDiscreteScheduler, DDIMScheduler); choose one explicitly");
  switch (*kind) {
    case SchedulerKind::EulerAncestral: return std::make_unique<EulerAncestralScheduler>(config);
    case SchedulerKind::Euler: return std::make_unique<EulerScheduler>(config);
    case SchedulerKind::Ddim: return std::make_unique<DdimScheduler>(config);
  }
  throw Error("unknown scheduler kind");
}

}  // namespace u3d::nn
