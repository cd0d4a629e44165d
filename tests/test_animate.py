"""tippedisk animate: a 3D animation of a stored run (plotting/animation.py, cli/animate.py)."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import tippedisk_analysis as td
from tippedisk_analysis.kinematics import rotation_from_euler
from tippedisk_analysis.plotting import animation

SRC = str(Path(__file__).resolve().parents[1] / "src")


@pytest.fixture(scope="module")
def ode_run():
    return td.simulate("ode-euler", 0.2, dt_output=0.005)


@pytest.fixture(scope="module")
def moreau_quaternion_run():
    return td.simulate("m6", 0.05, normalize_quaternion=True)


def _gif(path):
    with Image.open(path) as im:
        return im.n_frames, im.size


@pytest.mark.parametrize("which", ["ode_run", pytest.param("moreau_quaternion_run", marks=pytest.mark.slow)])
def test_cli_writes_the_frames_and_size_asked_for(which, request, tmp_path):
    ds = request.getfixturevalue(which)
    run, gif = tmp_path / "run.nc", tmp_path / "run.gif"
    td.save(ds, run)
    duration = float(ds.time[-1] - ds.time[0])
    speed, fps = duration / 1.5, 8.0  # 1.5 s of video: 13 frames
    proc = subprocess.run([sys.executable, "-m", "tippedisk_analysis.cli", "animate", str(run), "-o", str(gif),
                           "--speed", repr(speed), "--fps", "8", "--size", "320x180"],
                          capture_output=True, text=True, env={**os.environ, "PYTHONPATH": SRC})
    assert proc.returncode == 0, proc.stderr
    expected = int(np.floor(duration * fps / speed + 1e-9)) + 1
    assert _gif(gif) == (expected, (320, 180))
    assert f"{expected} frames" in proc.stdout
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.gif", "run.nc"]  # no temporary file left


@pytest.mark.parametrize("which", ["ode_run", "moreau_quaternion_run"])
def test_a_frame_shows_the_pose_of_the_dataset(which, request):
    """The drawn rim, G, S and C1 of one frame against the stored state at that time."""
    ds = request.getfixturevalue(which)
    k = ds.sizes["time"] // 2
    t = float(ds.time[k])
    disk = td.results.config_of(ds)["setup"]["disk"]
    anim = animation.Animator(ds, [t], size=(320, 180))
    try:
        anim.draw(0)
        rim = np.array(anim.rim.get_data_3d())
        G = np.array([a[0] for a in anim.g_mark.get_data_3d()])
        S = np.array([a[0] for a in anim.s_mark.get_data_3d()])
        C1 = np.array([a[0] for a in anim.c_mark.get_data_3d()])
    finally:
        anim.close()
    np.testing.assert_allclose(G, [float(ds.x[k]), float(ds.y[k]), float(ds.z[k])], atol=1e-12)
    assert S[2] == pytest.approx(float(ds.z_S[k]), abs=1e-9)  # the dataset's own z_S
    R = rotation_from_euler(float(ds.alpha[k]), float(ds.beta[k]), float(ds.gamma[k]))
    np.testing.assert_allclose(S - G, disk["e"] * R[:, 0], atol=1e-8)  # S on e_x^B at distance e
    offsets = rim - G[:, None]
    np.testing.assert_allclose(np.linalg.norm(offsets, axis=0), disk["r"], rtol=1e-9)  # the rim, radius r
    np.testing.assert_allclose(R[:, 2] @ offsets, 0.0, atol=1e-9)  # in the disk plane
    assert C1[2] == pytest.approx(float(ds.g_N1[k]), abs=1e-7)  # the lowest rim point is C1, at height g_N1
    assert rim[2].min() >= C1[2] - 1e-5  # nothing of the rim below C1 (up to the drawn polygon's resolution)


def test_frame_times_follow_speed_and_fps(ode_run):
    times = animation.frame_times(ode_run, speed=0.1, fps=30, t_start=0.05, t_stop=0.15)
    assert len(times) == 31 and times[0] == 0.05
    np.testing.assert_allclose(np.diff(times), 0.1 / 30)


@pytest.mark.parametrize("kwargs, fragment", [
    ({"speed": 0.0}, "speed"), ({"fps": 0}, "fps"), ({"t_start": 1.0}, "time window"),
    ({"size": (4, 4)}, "size"), ({"panels": ("zeta",)}, "side panel"),
])
def test_bad_options_are_refused_before_writing(ode_run, tmp_path, kwargs, fragment):
    with pytest.raises(td.ParameterError, match=fragment):
        animation.animate(ode_run, tmp_path / "a.gif", progress=False, **kwargs)
    assert list(tmp_path.iterdir()) == []


def test_only_simulations_with_samples_are_animated(ode_run, tmp_path):
    with pytest.raises(td.DatasetError, match="no samples"):
        animation.animate(ode_run.isel(time=slice(0, 0)), tmp_path / "a.gif", progress=False)
    with pytest.raises(td.ParameterError, match="ffmpeg|cannot write"):
        animation.animate(ode_run, tmp_path / ("a.mp4" if not animation.animation.writers.is_available("ffmpeg")
                                               else "a.txt"), progress=False)
    assert list(tmp_path.iterdir()) == []
