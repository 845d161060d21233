// Render: not written yet.
#pragma once
