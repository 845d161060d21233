// Renderer tests: not written yet.
