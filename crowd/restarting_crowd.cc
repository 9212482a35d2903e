#include "crowd/restarting_crowd.h"

namespace gk {

Result<std::unique_ptr<RestartingCrowd>> RestartingCrowd::create(Factory factory) {
  if (!factory) return Status::Error("restarting crowd: no factory");
  Result<std::unique_ptr<CrowdSource>> first = factory(0);
  if (!first.ok()) return first.status();
  if (!*first) return Status::Error("restarting crowd: round 0: the factory built no crowd");
  return std::unique_ptr<RestartingCrowd>(
      new RestartingCrowd(std::move(factory), std::move(*first)));
}

RestartingCrowd::RestartingCrowd(Factory factory, std::unique_ptr<CrowdSource> first)
    : factory_(std::move(factory)), current_(std::move(first)), capacity_(current_->capacity()) {
  round_had_agents_ = current_->frame().size() > 0;
}

Status RestartingCrowd::step(float dt_s) {
  // Everyone left on the frame shown last: the next round comes in (its first frame, unstepped),
  // so each agent of the old round was absent for at least that frame.
  if (round_had_agents_ && current_->frame().size() == 0) {
    const double now_s = time_s();
    Result<std::unique_ptr<CrowdSource>> next = factory_(round_ + 1);
    if (!next.ok()) return next.status();
    if (!*next) {
      return Status::Error("restarting crowd: round " + std::to_string(round_ + 1) +
                           ": the factory built no crowd");
    }
    if ((*next)->capacity() > capacity_) {
      return Status::Error("restarting crowd: round " + std::to_string(round_ + 1) + " has " +
                           std::to_string((*next)->capacity()) + " agents, more than the " +
                           std::to_string(capacity_) + " of the first");
    }
    current_ = std::move(*next);
    ++round_;
    round_start_s_ = now_s + dt_s - current_->time_s();
    round_had_agents_ = current_->frame().size() > 0;
    return Status::Ok();
  }
  GK_RETURN_IF_ERROR(current_->step(dt_s));
  round_had_agents_ = round_had_agents_ || current_->frame().size() > 0;
  return Status::Ok();
}

}  // namespace gk
