// FPS model: not written yet.
#pragma once
