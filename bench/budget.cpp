#include "bench/budget.h"

#include <cmath>

namespace canopy {
namespace {

// Values ordered so that memory grows from `low` to `high`.
struct Bracket {
  double low, high;
};

Bracket memoryOrdered(const MemoryKnob& knob) {
  return knob.memoryGrows ? Bracket{knob.lo, knob.hi} : Bracket{knob.hi, knob.lo};
}

double between(const MemoryKnob& knob, double a, double b) {
  if (knob.integer) return std::floor(0.5 * (a + b));
  return a > 0.0 && b > 0.0 ? std::sqrt(a * b) : 0.5 * (a + b);
}

// The next value towards `end`: twice (or half) the current one, at most `end`.
double expand(const MemoryKnob& knob, double value, double end) {
  double next =
      end > value ? std::max(value * 2.0, value + (knob.integer ? 1.0 : 0.0)) : value * 0.5;
  if (knob.integer) next = std::round(next);
  return end > value ? std::min(next, end) : std::max(next, end);
}

bool adjacent(const MemoryKnob& knob, double a, double b) {
  return knob.integer ? std::abs(a - b) <= 1.0 : std::abs(a - b) <= 1e-3 * std::abs(a + b);
}

struct Evaluator {
  const std::function<double(double)>& measure;
  KnobSearch& search;
  double operator()(double value) {
    const double measured = measure(value);
    ++search.steps;
    search.trace.emplace_back(value, measured);
    return measured;
  }
};

}  // namespace

KnobSearch bisectToTarget(const MemoryKnob& knob, double target, double tolerance,
                          const std::function<double(double)>& measure, int maxSteps) {
  KnobSearch search;
  Evaluator evaluate{measure, search};
  const auto within = [&](double m) { return std::abs(m - target) <= tolerance * target; };
  const auto keepBest = [&](double value, double m) {
    if (search.steps == 1 || std::abs(m - target) < std::abs(search.measured - target)) {
      search.value = value;
      search.measured = m;
    }
  };
  Bracket b = memoryOrdered(knob);
  const double low = evaluate(b.low);
  keepBest(b.low, low);
  if (within(low) || low > target) {
    search.reached = within(low);
    return search;
  }
  // Bracket the target from below, doubling the value (halving for shrinking knobs), so a huge
  // end of the range — gigabytes of texture — is never baked unless the budget asks for it.
  const double end = b.high;
  for (double next = expand(knob, b.low, end);; next = expand(knob, b.low, end)) {
    const double m = evaluate(next);
    keepBest(next, m);
    if (within(m)) {
      search.reached = true;
      return search;
    }
    if (m > target) {
      b.high = next;
      break;
    }
    b.low = next;
    if (next == end || search.steps >= maxSteps) return search;  // the whole range is too small
  }
  while (search.steps < maxSteps && !adjacent(knob, b.low, b.high)) {
    const double mid = between(knob, b.low, b.high);
    if (mid == b.low || mid == b.high) break;
    const double m = evaluate(mid);
    keepBest(mid, m);
    if (within(m)) break;
    (m < target ? b.low : b.high) = mid;
  }
  search.reached = within(search.measured);
  return search;
}

KnobSearch leastMemoryReaching(const MemoryKnob& knob, double target,
                               const std::function<double(double)>& quality, int maxSteps) {
  KnobSearch search;
  Evaluator evaluate{quality, search};
  Bracket b = memoryOrdered(knob);
  const double least = evaluate(b.low);
  search.value = b.low;
  search.measured = least;
  if (least >= target) {
    search.reached = true;
    return search;
  }
  // Grow from the cheap end until the target is reached (doubling), then bisect back.
  const double end = b.high;
  for (double next = expand(knob, b.low, end);; next = expand(knob, b.low, end)) {
    const double q = evaluate(next);
    search.value = next;
    search.measured = q;
    if (q >= target) {
      b.high = next;
      search.reached = true;
      break;
    }
    b.low = next;
    if (next == end || search.steps >= maxSteps) return search;  // not reachable in range
  }
  // Invariant: quality(low) < target <= quality(high).
  while (search.steps < maxSteps && !adjacent(knob, b.low, b.high)) {
    const double mid = between(knob, b.low, b.high);
    if (mid == b.low || mid == b.high) break;
    const double q = evaluate(mid);
    if (q >= target) {
      b.high = mid;
      search.value = mid;
      search.measured = q;
    } else {
      b.low = mid;
    }
  }
  return search;
}

}  // namespace canopy
