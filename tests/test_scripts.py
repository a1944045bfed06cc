import importlib.util
from pathlib import Path

import numpy as np

SCRIPTS = Path(__file__).resolve().parents[1] / "scripts"


def load_script(name: str):
    spec = importlib.util.spec_from_file_location(name, SCRIPTS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_prediction_r2_is_one_for_a_sine_and_zero_for_white_noise():
    prediction_r2 = load_script("ground_predictability").prediction_r2
    time = np.arange(3000) * 0.02
    assert prediction_r2(np.sin(7.0 * time), horizon=10) > 0.999
    noise = np.random.default_rng(0).standard_normal(3000)
    assert abs(prediction_r2(noise, horizon=1)) < 0.02
