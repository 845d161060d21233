// render.frames stage tests: not written yet.
