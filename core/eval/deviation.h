// Deviation of the patches from the Catmull-Clark limit surface.
//
// Regular patches are the limit exactly (an identity the tests check against OpenSubdiv), so
// only the zones around irregular vertices are measured. Construction Q reparametrizes the
// surface there (docs/math.md 5.6), so the measure is the closest-point distance: the zone is
// refined `sample_levels` more levels, the limit positions of the refined vertices are the
// samples, and each sample's distance to the nearest zone Bezier piece is found by Newton
// iteration.
#pragma once

#include <vector>

#include "core/patch/patch_builder.h"

namespace subd2nurbs {

struct FanDeviation {
  int fan = -1;        ///< index into PatchBuildInfo::fans
  double max = 0;      ///< model units
  int samples = 0;
  double sum = 0;      ///< of the sample distances (for the mean)
  Point3 where{};      ///< the sample with the largest distance
};

struct DeviationReport {
  double max = 0;     ///< model units; 0 when there is no irregular vertex
  double mean = 0;    ///< over all samples
  Point3 where{};     ///< the limit sample with the largest distance
  int worst_fan = -1; ///< index into PatchBuildInfo::fans, -1 if none
  int samples = 0;
  int sample_levels = 0;
  std::vector<FanDeviation> fans;
};

/// Closest-point deviation in the zones of every irregular-vertex fan. With `previous` (a
/// report on a build of the same cage, whose fans are numbered alike), only the fans with
/// `remeasure[fan]` set are measured again; the others keep their previous values.
DeviationReport measure_deviation(const PatchBuild& build, int sample_levels = 2,
                                  const DeviationReport* previous = nullptr,
                                  const std::vector<char>* remeasure = nullptr);

/// Asymptotic factor by which Construction Q's deviation falls per extra level at an
/// interior vertex of valence n: 1 / max(lambda_n^2, mu_n) (docs/math.md 5.6). 4 for n = 4.
double deviation_rate(int valence);

/// Extra levels after which one fan's deviation `max` falls to `tolerance`, extrapolated with
/// its rate: deviation_rate of its valence; crease and corner fans that of valence 2k and 4k
/// (k sectors), approximate fans 2 (a conservative guess: no rate is derived for them).
int fan_extra_levels_for_tolerance(const IrregularFan& fan, double max, double tolerance);

}  // namespace subd2nurbs
