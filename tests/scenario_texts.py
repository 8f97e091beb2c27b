"""Small scenario files shared by the command tests (32 chirps, 4 x 4 UPA, 12.8 us chirps)."""

from __future__ import annotations


def small_scenario(name: str, *, az_deg: float = 20.0, pitch_deg: float | None = None,
                   pitch_hz: float = 20.0, pitch_phase_deg: float | None = None,
                   frames: int | None = None) -> str:
    """TOML text of a one-target scenario, optionally with a pitch sinusoid.

    Parameters
    ----------
    name : str
        Scenario name.
    az_deg : float
        Azimuth of the target at 15 m [deg].
    pitch_deg, pitch_hz, pitch_phase_deg : float, optional
        Pitch sinusoid amplitude [deg], frequency [Hz] and phase [deg] (none without
        ``pitch_deg``).
    frames : int, optional
        Frames of the run.
    """
    lines = [f'name = "{name}"']
    if frames is not None:
        lines.append(f"frames = {frames}")
    lines += ["[radar]", "num_chirps = 32", "chirp_duration_s = 12.8e-6",
              "[array]", "nx = 4", "ny = 4",
              "[[scene.targets]]", "range_m = 15.0", f"az_deg = {az_deg}"]
    if pitch_deg is not None:
        lines += ["[[motion.sinusoids]]", 'axis = "pitch"', f"amplitude_deg = {pitch_deg}",
                  f"frequency_hz = {pitch_hz}"]
        if pitch_phase_deg is not None:
            lines.append(f"phase_deg = {pitch_phase_deg}")
    return "\n".join(lines) + "\n"
