// Tests (in progress).
