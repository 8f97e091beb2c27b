"""Tutorial 1: a point target seen from a pitching drone, and what compensation restores.

Run it from any folder (it writes nothing):

    python docs/tutorials/01_point_target.py

What it shows, in about ten seconds on a laptop:

1. a scenario written as TOML text (the same keys as a scenario file, see
   docs/user_guide.md section 3), kept small: 64 chirps, an 8 x 8 virtual
   array, one frame;
2. the radar frames rendered in memory: ``RadarFrame.data`` has shape
   ``[chirp, channel, sample]`` (complex IF samples);
3. the metrics of the point target through the chains ``none`` (no
   compensation), ``paper`` (the published chain) and ``exact`` (rigid-body
   projection), with the names and units of ``raysim.vocabulary.METRICS`` (name: unit,
   definition).

The pitch oscillation smears the target's Doppler and moves its angle; the
exact chain brings the pseudo-velocity back to about zero.
"""

from raysim.pipeline.run import evaluate
from raysim.pipeline.sources import render_frames
from raysim.scenario import loads_scenario
from raysim.vocabulary import METRICS

SCENARIO = """
name = "tutorial: pitching drone"
frames = 1
lever_arm_m = [0.0, 0.0, 0.1]       # radar phase centre in the body frame FRD [m]

[radar]
num_chirps = 64                     # the paper uses 256: smaller is faster

[array]
kind = "upa"                        # virtual uniform planar array, half a wavelength apart
nx = 8
ny = 8

[[scene.targets]]
range_m = 15.0
az_deg = 20.0
el_deg = 0.0
rcs_dbsm = 10.0

[[motion.sinusoids]]
axis = "pitch"
amplitude_deg = 10.0
frequency_hz = 20.0

[imu]
preset = "tactical"
rate_hz = 2000.0
"""


def main() -> dict:
    """Render the scenario, print the metrics per chain, return :func:`evaluate`'s result."""
    scenario = loads_scenario(SCENARIO, source="tutorial 1")
    cfg = scenario.radar_config()
    print(f"radar: {cfg.num_chirps} chirps x {scenario.virtual_array().num_channels} channels "
          f"x {cfg.num_samples} samples, motion: {scenario.trajectory().name}")

    frames = render_frames(scenario)                  # list of RadarFrame, one per frame
    print("IF cube [chirp, channel, sample]:", frames[0].data.shape)

    result = evaluate(scenario, chains=["none", "paper", "exact"], frames=frames)
    names = ["pseudo_velocity_mps", "doppler_width_hz", "angle_error_deg"]
    print(f"{'chain':8s}" + "".join(f"{n} [{METRICS[n][0]}]".rjust(28) for n in names))
    for chain, metrics in result["chains"].items():
        print(f"{chain:8s}" + "".join(f"{metrics[n]:28.3f}" for n in names))
    for chain, warnings in result["warnings"].items():
        for w in warnings:
            print(f"warning: {chain}: {w}")
    return result


if __name__ == "__main__":
    main()
