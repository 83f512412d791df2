"""ocio_vp.footage.distributed: the same results inline, in a local process pool and on Dask.

The reference is the plain in-process call; every path must give the same per-item results
and turn a failing task into a reported exception while the other tasks finish.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from conftest import make_measurements_dict

from ocio_vp.cli import main
from ocio_vp.errors import InputError
from ocio_vp.footage.distributed import map_unordered


def _sqrt_or_fail(x: float) -> float:
    if x < 0:
        raise ValueError(f"negative: {x}")
    return math.sqrt(x)


ITEMS = [4.0, 9.0, -1.0, 16.0, 25.0]


def _check(results):
    got = dict(results)
    assert sorted(got) == list(range(len(ITEMS)))
    assert isinstance(got[2], ValueError)
    assert [got[i] for i in (0, 1, 3, 4)] == [2.0, 3.0, 4.0, 5.0]


def test_inline():
    _check(map_unordered(_sqrt_or_fail, ITEMS, workers=1))


def test_local_process_pool():
    _check(map_unordered(_sqrt_or_fail, ITEMS, workers=2))


@pytest.fixture(scope="module")
def dask_scheduler():
    """The address of one in-process Dask cluster (threads) for this file's tests: quick to
    start, and a tcp:// scheduler takes the same path. The suite runs beside other work, where
    a thread may wait seconds for a core: Dask's connection and heartbeat timeouts are made
    generous (nothing here tests them), so only a wrong result can fail these tests."""
    distributed = pytest.importorskip("distributed")
    import dask

    patient = {
        "distributed.comm.timeouts.connect": "300s",
        "distributed.comm.timeouts.tcp": "300s",
        "distributed.scheduler.worker-ttl": "600s",
        "distributed.deploy.lost-worker-timeout": "300s",
    }
    with (
        dask.config.set(patient),
        distributed.LocalCluster(
            n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None
        ) as cluster,
    ):
        yield cluster.scheduler_address


def test_dask_cluster(dask_scheduler):
    _check(map_unordered(_sqrt_or_fail, ITEMS, scheduler=dask_scheduler))


def test_bad_scheduler_and_workers():
    with pytest.raises(InputError, match="scheduler address"):
        map_unordered(_sqrt_or_fail, ITEMS, scheduler="farm:8786")
    with pytest.raises(InputError, match="workers"):
        map_unordered(_sqrt_or_fail, ITEMS, workers=0)


def test_apply_with_two_local_workers(tmp_path):
    oiio = pytest.importorskip("OpenImageIO")
    doc = tmp_path / "stage.yaml"
    doc.write_text(yaml.safe_dump(make_measurements_dict(environments=1)))
    assert main(["solve", str(doc), "--out", str(tmp_path / "calib")]) == 0
    for f in range(1, 5):
        path = tmp_path / f"p.{f:04d}.exr"
        buf = oiio.ImageBuf(oiio.ImageSpec(8, 8, 3, "float"))
        oiio.ImageBufAlgo.fill(buf, (0.1 * f, 0.2, 0.3))
        assert buf.write(str(path))
    args = ["apply", str(tmp_path / "calib" / "env_0"), str(tmp_path / "p.%04d.exr")]
    assert main([*args, "--out", str(tmp_path / "pool"), "--workers", "2", "--no-progress"]) == 0
    assert main([*args, "--out", str(tmp_path / "one"), "--workers", "1", "--no-progress"]) == 0
    for f in range(1, 5):
        a = oiio.ImageBuf(str(tmp_path / "pool" / f"p.{f:04d}.exr")).get_pixels(oiio.FLOAT)
        b = oiio.ImageBuf(str(tmp_path / "one" / f"p.{f:04d}.exr")).get_pixels(oiio.FLOAT)
        np.testing.assert_array_equal(a, b)


def test_solve_on_dask_matches_local(tmp_path, dask_scheduler):
    import json

    doc = tmp_path / "stage.yaml"
    doc.write_text(yaml.safe_dump(make_measurements_dict(environments=2)))
    args = ["solve", str(doc), "--scheduler", dask_scheduler]
    assert main([*args, "--out", str(tmp_path / "dask")]) == 0
    assert main(["solve", str(doc), "--out", str(tmp_path / "local")]) == 0
    for env in ("env_0", "env_1"):
        a = json.loads((tmp_path / "dask" / env / "solution.json").read_text())
        b = json.loads((tmp_path / "local" / env / "solution.json").read_text())
        assert a == b
