#!/usr/bin/env python3
"""FORM with OpenTURNS over truss_deploy: the probability that the peak drive force of a deployment
exceeds a threshold, when the diagonals' stiffness K and free length l_0 and the strut length l_s
scatter, from FORM (and SORM, its curvature correction) against a crude Monte Carlo estimate.

The mast is the paper's Table 1 mast with 10 bays, deployed at constant speed (the peak drive force
is reached in the first bay's stage, the same for 10 or 30 bays; 10 make the Monte Carlo cheaper).
OpenTURNS calls the simulator through a PythonFunction whose sample evaluation is one
simulate_many call, so that each batch of runs (Monte Carlo blocks, finite differences) uses every
core.

    /usr/bin/python3 examples/openturns_form.py [--threshold 3.5] [--mc-runs 20000] [--json out.json]
"""
import argparse
import json
import math
import time

import numpy as np
import openturns as ot

import truss_deploy as td

BASE = td.Scene.table1().with_(**{"mast.n_bays": 10})
# The scattered inputs: scene keys with their distributions (mean from Table 1, standard deviation).
INPUTS = {
    "mast.diagonal_stiffness_N_per_m": ot.Normal(20.0, 1.0),   # N/m, 5 % of K
    "mast.diagonal_free_length_m": ot.Normal(0.45, 0.002),     # m, a 2 mm tolerance on l_0
    "mast.strut_length_m": ot.Normal(0.18, 0.0005),            # m, a 0.5 mm tolerance on l_s
}


def peak_drive_force(sample):
    """The model for OpenTURNS: one row of inputs per run -> the peak drive force in N."""
    x = np.asarray(sample)
    df = td.simulate_many(BASE, {k: x[:, i] for i, k in enumerate(INPUTS)}, bays=False)
    bad = df[df.status != "ok"]
    if len(bad):  # a failed run is data, but this study's model has no value for it: say so
        raise RuntimeError(f"{len(bad)} runs did not end ok, e.g. {bad.status.iloc[0]}: {bad.message.iloc[0]}")
    return df[["peak_drive_force_N"]].to_numpy()


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--threshold", type=float, default=3.5, help="peak drive force threshold in N (default 3.5)")
    ap.add_argument("--mc-runs", type=int, default=20000, help="crude Monte Carlo runs (default 20000)")
    ap.add_argument("--seed", type=int, default=1, help="OpenTURNS' random seed")
    ap.add_argument("--json", help="also write the results to this JSON file")
    a = ap.parse_args()

    ot.RandomGenerator.SetSeed(a.seed)
    inputs = ot.ComposedDistribution(list(INPUTS.values()))
    inputs.setDescription(list(INPUTS))
    model = ot.MemoizeFunction(ot.PythonFunction(len(INPUTS), 1, func_sample=peak_drive_force))
    force = ot.CompositeRandomVector(model, ot.RandomVector(inputs))
    event = ot.ThresholdEvent(force, ot.Greater(), a.threshold)

    t0 = time.perf_counter()
    form = ot.FORM(ot.AbdoRackwitz(), event, inputs.getMean())
    form.run()
    res = form.getResult()
    # SORM: the same design point search (its runs remembered by MemoizeFunction), then the curvatures.
    sorm = ot.SORM(ot.AbdoRackwitz(), event, inputs.getMean())
    sorm.run()
    n_form = model.getInputHistory().getSize()
    t_form = time.perf_counter() - t0

    t0 = time.perf_counter()
    block = 1000
    mc = ot.ProbabilitySimulationAlgorithm(event, ot.MonteCarloExperiment())
    mc.setBlockSize(block)  # each block is one simulate_many call
    mc.setMaximumOuterSampling(max(1, a.mc_runs // block))
    mc.setMaximumCoefficientOfVariation(0.0)  # run every block
    mc.run()
    mc_res = mc.getResult()
    t_mc = time.perf_counter() - t0

    out = {
        "threshold_N": a.threshold,
        "inputs": list(INPUTS),
        "design_point_physical": list(res.getPhysicalSpaceDesignPoint()),
        "design_point_standard": list(res.getStandardSpaceDesignPoint()),
        "beta": res.getHasoferReliabilityIndex(),
        "pf_form": res.getEventProbability(),
        "pf_sorm_breitung": sorm.getResult().getEventProbabilityBreitung(),
        "form_sorm_evaluations": n_form,
        "pf_mc": mc_res.getProbabilityEstimate(),
        "pf_mc_std": math.sqrt(mc_res.getVarianceEstimate()),
        "mc_runs": mc_res.getOuterSampling() * mc_res.getBlockSize(),
    }
    print(f"P(peak drive force > {a.threshold} N), {len(INPUTS)} scattered inputs:")
    print(f"  FORM           {out['pf_form']:.4e}  (beta = {out['beta']:.4f})")
    print(f"  SORM Breitung  {out['pf_sorm_breitung']:.4e}  ({n_form} runs for FORM and SORM, {t_form:.2f} s)")
    print(f"  Monte Carlo    {out['pf_mc']:.4e} +- {1.96 * out['pf_mc_std']:.1e} (95 %)  "
          f"({out['mc_runs']} runs, {t_mc:.2f} s)")
    print("  design point:  " + ", ".join(f"{k} = {v:.6g}" for k, v in zip(INPUTS, out["design_point_physical"])))
    if a.json:
        with open(a.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
