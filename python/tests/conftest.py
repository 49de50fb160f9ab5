"""Shared fixtures of the hashfusion Python tests: a small synthetic camera and sequence, the CLI, temp folders.

Run from CTest (python/CMakeLists.txt sets PYTHONPATH to the build tree's package and HF_CLI to the hashfusion
executable), or by hand: PYTHONPATH=build/release/python HF_CLI=build/release/apps/hashfusion python3 -m pytest
python/tests
"""
import os
import subprocess

import pytest

import hashfusion as hf


@pytest.fixture(scope="session")
def camera():
    """320x240 (the 'ros' preset one level down): four times cheaper than 640x480, still tracks the room."""
    return hf.Camera.preset("ros").scaled(1)


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("HF_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("HF_CLI (the hashfusion executable) not set; CTest sets it")
    return path


def run_cli(cli, *args):
    """Runs the hashfusion CLI; returns its CompletedProcess (stdout, stderr as text)."""
    return subprocess.run([cli, *args], capture_output=True, text=True, timeout=300)


@pytest.fixture
def synthetic(camera):
    """A factory: open_dataset('synthetic:PRESET') at the small camera."""
    def make(frames=8, preset="room", seed=0):
        return hf.open_dataset("synthetic:" + preset, camera=camera, frames=frames, seed=seed)
    return make
