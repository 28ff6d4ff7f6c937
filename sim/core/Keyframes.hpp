#pragma once
// Keyframe interpolation shared by everything a scene animates with [[... .keys]] tables (the
// magnets' tracks, the spikes' look): the cubic Hermite basis and the monotone (PCHIP)
// tangent of a scalar channel. Header-only templates over a key type with a `time` member
// [s] and an accessor for the channel's value, so each owner keeps its own key struct.
#include <algorithm>
#include <cstddef>
#include <vector>

namespace ferro {

/// Cubic Hermite basis on u in [0, 1] between values p0 and p1 with tangents m0, m1 per unit
/// time over a segment of dt [s] (hence the dt factor).
template <class T>
T hermite(const T& p0, const T& p1, const T& m0, const T& m1, double dt, double u)
{
    const double u2 = u * u, u3 = u2 * u;
    return (2 * u3 - 3 * u2 + 1) * p0 + (u3 - 2 * u2 + u) * dt * m0 + (-2 * u3 + 3 * u2) * p1 + (u3 - u2) * dt * m1;
}

/// Secant slope of channel `value` between keys i and i + 1 (0 for coincident times).
template <class Key, class Get>
double keySecant(const std::vector<Key>& k, size_t i, Get value)
{
    const double dt = k[i + 1].time - k[i].time;
    return dt > 0.0 ? (value(k[i + 1]) - value(k[i])) / dt : 0.0;
}

/// Fritsch-Butland (PCHIP) tangent at key j: weighted harmonic mean of the adjacent secants,
/// zero at a local extremum, so the interpolant stays monotone between keys and never
/// overshoots them (a strength or a gain keyed 0 -> 1 -> 1 never goes above 1 or below 0).
template <class Key, class Get>
double monotoneTangent(const std::vector<Key>& k, size_t j, Get value)
{
    const size_t n = k.size();
    if (n < 2) return 0.0;
    if (j == 0) return keySecant(k, 0, value);
    if (j == n - 1) return keySecant(k, n - 2, value);
    const double d0 = keySecant(k, j - 1, value), d1 = keySecant(k, j, value);
    if (d0 * d1 <= 0.0) return 0.0;
    const double h0 = k[j].time - k[j - 1].time, h1 = k[j + 1].time - k[j].time;
    const double w0 = 2 * h1 + h0, w1 = h1 + 2 * h0;
    return (w0 + w1) / (w0 / d0 + w1 / d1);
}

/// The segment of keys (sorted by time, at least two) that holds t: i with
/// k[i].time <= t < k[i + 1].time, for k.front().time < t < k.back().time.
template <class Key>
size_t keySegment(const std::vector<Key>& k, double t)
{
    const auto it = std::upper_bound(k.begin(), k.end(), t, [](double v, const Key& key) { return v < key.time; });
    return size_t(it - k.begin()) - 1;
}

/// Channel `value` at time t [s], monotone cubic between keys sorted by time; before the first
/// key its value, after the last the last's. No keys: `fallback`.
template <class Key, class Get>
double monotoneKeyValue(const std::vector<Key>& k, double t, Get value, double fallback)
{
    if (k.empty()) return fallback;
    if (k.size() == 1 || !(t > k.front().time)) return value(k.front());
    if (t >= k.back().time) return value(k.back());
    const size_t i = keySegment(k, t);
    const double dt = k[i + 1].time - k[i].time;
    if (!(dt > 0.0)) return value(k[i + 1]);
    return hermite<double>(value(k[i]), value(k[i + 1]), monotoneTangent(k, i, value),
                           monotoneTangent(k, i + 1, value), dt, (t - k[i].time) / dt);
}

} // namespace ferro
