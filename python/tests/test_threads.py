"""Long calls release the GIL, and Ctrl-C (SIGINT) ends Pipeline.run after the current frame with
KeyboardInterrupt, keeping the frames processed."""
import os
import signal
import threading

import pytest

import hashfusion as hf

FRAMES = 40


def test_gil_released_during_run(synthetic):
    data = synthetic(frames=10)
    p = hf.Pipeline(None, data.camera)
    done = threading.Event()
    worker = threading.Thread(target=lambda: (p.run(data), done.set()))
    ticks = 0
    worker.start()
    while not done.is_set():  # runs only while the worker is inside C++ without the GIL
        ticks += 1
        done.wait(0.001)
    worker.join()
    assert p.frames_processed == 10
    # ten frames take far over 10 ms; a run holding the GIL would leave this loop no turn until it ends
    assert ticks > 10


def test_ctrl_c_interrupts_run(synthetic):
    data = synthetic(frames=FRAMES)
    p = hf.Pipeline(None, data.camera)
    second = threading.Event()
    # SIGINT once two frames are done: it lands while the main thread is inside run() (in C++, or in the callback)
    timer = threading.Thread(target=lambda: (second.wait(60), os.kill(os.getpid(), signal.SIGINT)))
    seen = []
    def callback(result):
        seen.append(result.index)
        if len(seen) == 2:
            second.set()
    original = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        timer.start()
        with pytest.raises(KeyboardInterrupt):
            p.run(data, callback=callback)
        timer.join()
    finally:
        signal.signal(signal.SIGINT, original)
    # the frame in flight when the signal came is processed (its callback may be the one interrupted)
    assert 2 <= len(seen) <= p.frames_processed < FRAMES and seen == list(range(len(seen)))
    # the pipeline and the dataset stay usable: the next frame is processed as usual
    assert p.process(next(data)).index == p.frames_processed - 1


def test_callback_exception_stops_run(synthetic):
    data = synthetic(frames=5)
    p = hf.Pipeline(None, data.camera)
    def callback(result):
        if result.index == 1:
            raise RuntimeError("enough")
    with pytest.raises(RuntimeError, match="enough"):
        p.run(data, callback=callback)
    assert p.frames_processed == 2
