// Report tests: not written yet.
