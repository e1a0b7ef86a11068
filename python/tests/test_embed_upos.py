"""hbid.embed and hbid.upos: the command line's delay, embedding dimension and orbits."""

from __future__ import annotations

import json
import pickle
import subprocess

import numpy as np
import pytest

import hbid


def test_embed_finds_the_first_minimum_and_the_dimension(pendulum):
    e = hbid.embed(pendulum.x, t=pendulum.t)
    d = e.delay
    assert 1 <= d < len(e.ami) - 1
    assert e.ami[d] < e.ami[d - 1] and e.ami[d] <= e.ami[d + 1]
    assert len(e.ami) == 2 * 25 + 1
    assert len(e.fnn) == 8 and e.metric == "circle"
    assert e.embedding_dimension is not None
    assert e.fnn[e.embedding_dimension - 1] < e.fraction_threshold
    assert all(f >= e.fraction_threshold for f in e.fnn[: e.embedding_dimension - 1])
    j = json.loads(e.to_json())
    assert j["delay"] == d and j["embedding_dimension"] == e.embedding_dimension
    assert np.array_equal(j["ami"], e.ami) and np.array_equal(j["fnn"], e.fnn)
    assert pickle.loads(pickle.dumps(e)).delay == d


def test_embed_options(pendulum):
    linear = hbid.embed(pendulum.x, t=pendulum.t, metric="linear", max_lag=30, max_dim=4, bins=8)
    assert linear.metric == "line" and len(linear.ami) == 31 and len(linear.fnn) == 4
    with pytest.raises(hbid.OptionsError, match="bins=1: must be between 2 and 1024"):
        hbid.embed(pendulum.x, t=pendulum.t, bins=1)
    with pytest.raises(hbid.OptionsError, match="max_dim=0: must be between 1 and 8"):
        hbid.embed(pendulum.x, t=pendulum.t, max_dim=0)
    with pytest.raises(hbid.OptionsError, match="metric='taxi'"):
        hbid.embed(pendulum.x, t=pendulum.t, metric="taxi")


def test_embed_and_upos_json_match_the_command_line(tmp_path, pendulum, cli):
    path = tmp_path / "r.csv"
    np.savetxt(path, np.c_[pendulum.t, pendulum.x], delimiter=",", header="t,theta", comments="", fmt="%.17g")
    record = hbid.read(path)
    for name, ours in (("embed", hbid.embed(record)), ("upos", hbid.upos(record))):
        out = subprocess.run([str(cli), "--quiet", name, str(path), "--json"], capture_output=True, text=True, check=True)
        assert json.loads(ours.to_json()) == json.loads(out.stdout), name


def test_upos_finds_orbits(pendulum):
    orbits = hbid.upos(pendulum.x, t=pendulum.t)
    assert len(orbits.segments) > 0 and orbits.distinct_orbits > 0
    assert orbits.tolerance == pytest.approx(0.03 * 2 * np.pi)
    assert all(1 <= s.period <= 16 and 0 <= s.error <= orbits.tolerance for s in orbits.segments)
    assert all(0 <= s.start <= 3000 - 25 * s.period for s in orbits.segments)
    assert len(orbits.orbit_of_segment) == len(orbits.segments)
    assert max(orbits.orbit_of_segment) == orbits.distinct_orbits - 1
    j = json.loads(orbits.to_json())
    assert j["segments"] == len(orbits.segments)
    assert {k: v for k, v in j["by_period"].items() if v} == {str(k): v for k, v in orbits.by_period.items()}
    tight = hbid.upos(pendulum.x, t=pendulum.t, tolerance=0.01, max_period=4, delay=orbits.delay)
    assert len(tight.segments) < len(orbits.segments)
    assert all(s.period <= 4 and s.error <= tight.tolerance for s in tight.segments)
    assert pickle.loads(pickle.dumps(orbits)) == orbits


def test_upos_bad_options(pendulum):
    with pytest.raises(hbid.OptionsError, match="tolerance"):
        hbid.upos(pendulum.x, t=pendulum.t, tolerance=0.7)
    with pytest.raises(hbid.OptionsError):
        hbid.upos(pendulum.x, t=pendulum.t, max_period=0)
    with pytest.raises(hbid.InputError):
        hbid.upos(pendulum.x, t=np.zeros_like(pendulum.t))
