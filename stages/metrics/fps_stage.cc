// estimate.fps: not written yet.
