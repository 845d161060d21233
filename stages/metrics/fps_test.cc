// estimate.fps tests: not written yet.
