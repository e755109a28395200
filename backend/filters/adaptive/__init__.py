"""The default filter: a still/moving interacting multiple model that learns its noise.

Why this design (docs/experiments/filters/README.md has the numbers): a Kalman filter tuned for
one noise level is wrong at the others (3 mm assumed, 20 mm real: worse than no filter), and the
paper's filter is precise on a still object but lags a moving one. No single (q, r) pair fits a
resting ball and a kicked one, so this filter carries two motion models and lets the data pick:

* **still**: the position is constant (a tiny random walk); its estimate is the running mean,
  the most precise thing a still object allows, and its velocity is exactly zero;
* **moving**: constant velocity with white acceleration (a robot driving, a rolling ball).

They are mixed as an IMM (Blom & Bar-Shalom): per step the model probabilities follow a Markov
chain, each model starts from the mix of both, and the output is the probability-weighted
combination. The noise is learnt from the data, once per instant: the measurement noise ``r``
from the second differences of the measurements used (independent of the motion model),
averaged over a sliding horizon; the moving model's ``q`` from its normalised innovations and
their bias; the outlier rate from the gate's verdicts.

Beside the moving model (2-D only) runs a **cruise** model: constant velocity with a small *fixed*
q (``cruise_accel_mm_s2``, the straight run's). Why: the moving model's q is estimated, and an
estimate raised by a maneuver, or by a noise sequence that looks like one (one 4-sigma
measurement at 20 mm noise sets q to its bound; the start of a track with r not yet learnt drives
it up for a second), decays only over a second or so; on a straight run the estimate meanwhile
follows the noise (the constant-speed cells at 20 mm, 1.10-1.125 x the oracle on seeds 7, 11,
2022 with 40 runs). The two are weighed by their likelihood ratio (a two-state Markov chain,
``cruise_switch_per_s``): on a straight run the cruise model's narrower prediction wins and the
estimate keeps its low-q smoothness whatever q does; at a bounce its innovations explode, it is
ruled out within a frame or two and the adaptive q carries the estimate. It is not mixed with
the moving model (a three-model IMM's mixing would cost more than the model); once all but ruled out
(probability 1e-3) it rests for ``cruise_rest_s`` (0.1 s: the moving model alone, a turning
robot does not pay for it every step) and restarts from the moving model's state, which is what
the mixing would do then. The moving model's q learns from its own innovations as before. Cost:
2.8 -> 3.6 us per 2-D step, +9 to +12 us per world-model frame of 22 robots and a ball
(bench/world_bench.py: about 103 us against Kalman's 94 then; 83 against 56 since the revise
and the world model's cheaper merge, docs/experiments/filters/README.md).

Outliers and maneuvers (a kick, a bounce) both show up as a measurement far outside the gate;
``outliers.py`` tells them apart.

Where each part lives:

- ``step.py``: ``AdaptiveIMM`` and ``AdaptiveIMM1D``: the step, written once for both: the
  noise estimates learn, the still and moving (and cruise) models are mixed, predicted
  (``update``) and corrected (``revise``, also a second camera's measurement);
- ``outliers.py``: a measurement outside the gates: outlier, maneuver, re-acquisition, q
  raised and the step redone, the step after a jump;
- ``state.py``: the parameters, the state list's layout, starting and forgetting a track, and
  the outputs (estimate, velocity, prediction).

These are one class in three parts (``AdaptiveIMM`` -> ``Outliers`` -> ``AdaptiveState``): the
step calls the others as methods, as it did when they were one file, so a measurement costs
the same calls.
"""

from .step import BIAS_A, BIAS_K, AdaptiveIMM, AdaptiveIMM1D

__all__ = ["BIAS_A", "BIAS_K", "AdaptiveIMM", "AdaptiveIMM1D"]
