#include "controller/linuxcnc_planner.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <limits>

#include "util/parallel.hpp"
#include "util/parallel_select.hpp"
#include "util/progress.hpp"

namespace taxopt::controller {

/// Blocks followed between two looks at the job's stop (each some hundred servo periods).
constexpr std::size_t kBlocksBetweenLooks = 64;

/// The joints (the tip's machine position, A, C) on `b` with every axis's acceleration limit
/// scaled by `accel_scale` (1: the machine's), sampled each 1 ms servo period and differenced
/// over 10 (the window of scripts/linuxcnc_controller.py), the motion before and after the
/// block extended at its end velocities. Raises `peaks` (kJointCount of them) where the block
/// exceeds them. Ramps that do not fit in the block are cut at its ends (a chain's first or
/// last block shorter than its ramp: the blocks beside it are not followed). The block's
/// acceleration is its `accel_share` of the path's (a chain's first block LinuxCNC blends
/// parabolically with the next: half, program_time); a rapid and the last feed block before
/// one run at the full acceleration (measured to 0.01 mm/s^2). A bound on a chain's first
/// block of X Y Z alone: LinuxCNC may blend it parabolically too (at half).
void tcp_block_peaks(const Machine& machine, const TcpBlock& b, double accel_scale,
                     std::vector<JointPeak>& peaks) {
  constexpr std::size_t kA = static_cast<std::size_t>(Joint::Tilt);
  constexpr std::size_t kC = static_cast<std::size_t>(Joint::C);
  // The path u in [0, 1]: its velocity and acceleration limits from the axes that move.
  double u_vel = b.rate_per_s > 0.0 ? b.rate_per_s : std::numeric_limits<double>::infinity();
  double u_acc = std::numeric_limits<double>::infinity();
  for (std::size_t j = 0; j < kJointCount; ++j) {
    const double d = std::abs(b.to[j] - b.from[j]);
    if (d < 1e-12) continue;
    if (b.limits[j].max_velocity_per_s > 0.0) {
      u_vel = std::min(u_vel, b.limits[j].max_velocity_per_s / d);
    }
    if (b.limits[j].max_accel_per_s2 > 0.0) {
      u_acc = std::min(u_acc, accel_scale * b.accel_share * b.limits[j].max_accel_per_s2 / d);
    }
  }
  if (!std::isfinite(u_vel) || !std::isfinite(u_acc)) return;  // no move, or no limits to plan on
  if (!b.start_rest && !b.end_rest) return;  // the schedule's: joint rates along the chain
  // u(t) over [0, total_s]: a ramp up from rest (start_rest), a cruise, a ramp down to rest
  // (end_rest); v_in and v_out its velocities at the ends.
  double t_up = b.start_rest ? u_vel / u_acc : 0.0, t_down = b.end_rest ? u_vel / u_acc : 0.0;
  double top = u_vel;
  const double ramps_u = 0.5 * u_acc * (t_up * t_up + t_down * t_down);
  if (ramps_u >= 1.0) {
    // The ramps meet: the top velocity is what the block's length allows.
    top = std::sqrt(u_acc / ((b.start_rest ? 0.5 : 0.0) + (b.end_rest ? 0.5 : 0.0)));
    t_up = b.start_rest ? top / u_acc : 0.0;
    t_down = b.end_rest ? top / u_acc : 0.0;
  }
  const double cruise_s =
      std::max(0.0, (1.0 - 0.5 * u_acc * (t_up * t_up + t_down * t_down)) / std::max(top, 1e-300));
  const double total_s = t_up + cruise_s + t_down;
  const double v_in = b.start_rest ? 0.0 : top, v_out = b.end_rest ? 0.0 : top;
  const auto u_at = [&](double t) {
    if (t <= 0.0) return v_in * t;
    if (t >= total_s) return 1.0 + v_out * (t - total_s);
    if (t < t_up) return 0.5 * u_acc * t * t;
    const double up_u = 0.5 * u_acc * t_up * t_up;
    if (t < t_up + cruise_s) return up_u + top * (t - t_up);
    const double r = total_s - t;
    return b.end_rest ? 1.0 - 0.5 * u_acc * r * r : 1.0 - top * r;
  };
  const auto joints_at = [&](double t) {
    const double u = u_at(t);
    JointPosition p{};
    for (std::size_t j = 0; j < kJointCount; ++j) p[j] = b.from[j] + u * (b.to[j] - b.from[j]);
    const Posed pose{deg_to_rad(p[kA]), deg_to_rad(p[kC])};
    const Vec3d m = machine.rotary.to_machine_mm(Vec3d(p[0], p[1], p[2]), pose);
    return JointPosition{m.x(), m.y(), m.z(), p[kA], p[kC]};
  };
  // The joints once per servo period from two windows before the block to two after it, the
  // last 2 kWindow + 1 of them kept (a ring), differenced by index about the middle one.
  constexpr double kPeriodS = 1e-3;
  constexpr long kWindow = 10;
  constexpr double kWindowS = static_cast<double>(kWindow) * kPeriodS;
  const long steps = static_cast<long>(std::ceil((total_s + 4.0 * kWindowS) / kPeriodS));
  if (steps > 10'000'000) return;  // a block of hours: no controller test runs it
  std::array<JointPosition, 2 * kWindow + 1> ring{};
  const auto at = [&](long i) -> const JointPosition& {
    return ring[static_cast<std::size_t>(i % static_cast<long>(ring.size()))];
  };
  peaks.resize(kJointCount);
  for (long i = 0; i <= steps; ++i) {
    ring[static_cast<std::size_t>(i % static_cast<long>(ring.size()))] =
        joints_at(-2.0 * kWindowS + static_cast<double>(i) * kPeriodS);
    if (i < 2 * kWindow) continue;
    const JointPosition &before = at(i - 2 * kWindow), &here = at(i - kWindow), &after = at(i);
    for (std::size_t j = 0; j < kJointCount; ++j) {
      const double v = std::abs(after[j] - before[j]) / (2.0 * kWindowS);
      const double a = std::abs(after[j] - 2.0 * here[j] + before[j]) / (kWindowS * kWindowS);
      if (v > peaks[j].velocity_per_s) peaks[j].velocity_per_s = v, peaks[j].velocity_line = b.line;
      if (a > peaks[j].accel_per_s2) peaks[j].accel_per_s2 = a, peaks[j].accel_line = b.line;
    }
  }
}

/// GcodeProgram::tcp_joint_peaks of `blocks` with the axes' accelerations scaled by
/// `accel_scale`.
std::vector<JointPeak> tcp_joint_peaks(const Machine& machine, const std::vector<TcpBlock>& blocks,
                                       double accel_scale, const StopSource* stop) {
  using Peaks = std::vector<JointPeak>;
  // Blocks in parallel (a program of 143,840 points is 40 million servo periods); a later
  // chunk's peak replaces an earlier one's only when larger, as a later block's does.
  return detail::parallel_reduce(
      0, blocks.size(), Peaks{},
      [&](std::size_t lo, std::size_t hi, Peaks acc) {
        for (std::size_t i = lo; i < hi; ++i) {
          detail::look_at_stop(stop, i, kBlocksBetweenLooks);
          tcp_block_peaks(machine, blocks[i], accel_scale, acc);
        }
        return acc;
      },
      [](Peaks left, const Peaks& right) {
        if (left.empty()) return right;
        for (std::size_t j = 0; j < right.size() && j < left.size(); ++j) {
          if (right[j].velocity_per_s > left[j].velocity_per_s) {
            left[j].velocity_per_s = right[j].velocity_per_s;
            left[j].velocity_line = right[j].velocity_line;
          }
          if (right[j].accel_per_s2 > left[j].accel_per_s2) {
            left[j].accel_per_s2 = right[j].accel_per_s2;
            left[j].accel_line = right[j].accel_line;
          }
        }
        return left;
      });
}

/// The largest share of the axes' acceleration limits (0.001 steps, rounded down) at which
/// `blocks` keep every joint within its own (joint_accel_limit); 0 where none down to 0.05
/// does (the joints' speed, not the axes' acceleration, drives them). The peaks fall as the
/// share does (the ramps' slope with it; a short block's top speed too), so a bisection finds
/// it; only the blocks past a limit at the full share are followed.
double tcp_axis_accel_scale(const Machine& machine, const JointLimits& limits,
                            const std::vector<TcpBlock>& blocks, const StopSource* stop) {
  const auto worst_of = [&](const std::vector<JointPeak>& peaks) {
    double r = 0.0;
    for (std::size_t j = 0; j < peaks.size(); ++j) {
      const double a_max = joint_accel_limit(machine, limits, j);
      if (a_max > 0.0) r = std::max(r, peaks[j].accel_per_s2 / a_max);
    }
    return r;
  };
  const auto worst = [&](const std::vector<TcpBlock>& of, double scale) {
    return worst_of(tcp_joint_peaks(machine, of, scale, stop));
  };
  // A joint at its limit to the last bits (a rotary axis, which is its own joint, ramping at
  // its limit) is within it.
  const auto past = [](double ratio) { return ratio > 1.0 + 1e-9; };
  std::vector<TcpBlock> over;
  // Each block alone, the blocks in parallel (one block's peaks need no reduction of their own).
  const std::vector<std::size_t> past_alone =
      detail::parallel_select(0, blocks.size(), [&](std::size_t i) {
        detail::look_at_stop(stop, i, kBlocksBetweenLooks);
        std::vector<JointPeak> peaks;
        tcp_block_peaks(machine, blocks[i], 1.0, peaks);
        return past(worst_of(peaks));
      });
  for (std::size_t i : past_alone) over.push_back(blocks[i]);
  if (over.empty()) return 1.0;
  constexpr double kLeast = 0.05;
  if (past(worst(over, kLeast))) return 0.0;
  double lo = kLeast, hi = 1.0;  // lo keeps the joints within, hi does not
  while (hi - lo > 1e-4) {
    const double mid = 0.5 * (lo + hi);
    (past(worst(over, mid)) ? hi : lo) = mid;
  }
  const double scale = std::floor(lo * 1000.0) / 1000.0;
  return past(worst(over, scale)) ? 0.0 : scale;
}

namespace {

/// A move turns A or C from `from`.
bool turns(const GcodeMove& from, const GcodeMove& to) {
  return std::abs(to.tilt_deg - from.tilt_deg) > 1e-9 || std::abs(to.c_deg - from.c_deg) > 1e-9;
}

/// A line that is more than blanks and comments: a word the controller acts on.
bool has_word(const std::string& line) {
  int depth = 0;
  for (const char ch : line) {
    if (ch == ';') return false;
    if (ch == '(') ++depth;
    if (depth == 0 && !std::isspace(static_cast<unsigned char>(ch))) return true;
    if (ch == ')' && depth > 0) --depth;
  }
  return false;
}

}  // namespace

std::vector<bool> half_accel_rapids(const std::vector<GcodeMove>& moves, const std::string& text) {
  std::vector<std::size_t> starts{0};  // where each line of `text` begins
  for (std::size_t k = 0; k < text.size(); ++k) {
    if (text[k] == '\n') starts.push_back(k + 1);
  }
  const auto line_of = [&](int n) {
    const auto at = static_cast<std::size_t>(n - 1);
    if (n < 1 || at >= starts.size()) return std::string();
    const std::size_t end = at + 1 < starts.size() ? starts[at + 1] : text.size();
    return text.substr(starts[at], end - starts[at]);
  };
  std::vector<bool> half(moves.size(), false);
  for (std::size_t k = 0; k < moves.size(); ++k) {
    if (!moves[k].rapid) continue;
    if (k + 1 == moves.size()) {
      half[k] = true;
      continue;
    }
    const GcodeMove& next = moves[k + 1];
    bool stops = false;
    for (int n = moves[k].line + 1; n < next.line && !stops; ++n) stops = has_word(line_of(n));
    const GcodeMove* prev = k > 0 ? &moves[k - 1] : nullptr;
    const bool turning = (prev && turns(*prev, moves[k])) || turns(moves[k], next);
    half[k] = stops || (next.rapid && turning);
  }
  return half;
}

}  // namespace taxopt::controller
