// render.frames: not written yet.
