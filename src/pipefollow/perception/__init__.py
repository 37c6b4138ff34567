"""Perception: the downward camera's grey image of the footprint and a pipe detector on it; a sonar.

``water`` holds the one parameter record of water and camera settings, ``pixels`` the image's
pixel ↔ camera-metre conventions, ``image`` renders the footprint as the camera sees it,
``detector`` finds the pipe in a grey image (OpenCV, the optional extra ``vision``; its edge
stages in ``detector_edges``, its legs in ``detector_legs``, its second look at the border in
``detector_border``), ``follow``
walks along the pipe's edges to the ends of the visible piece (and holds the least-squares edge
fit both use), and ``camera`` joins them to the simulation's observation slots. ``tracker``
follows the pipe over the frames (its compiled step in ``track_step``, its filter in ``line_ekf``,
its memory of the pieces shown in ``piece_memory``, the vehicle's motion from ``navigation``).
``sonar`` renders a multibeam profiler's ping, ``sonar_detect`` finds the pipe in it and ``sonar_track`` turns
successive detections into the camera's observation; ``sensor`` gives the environments camera, sonar or both.
"""

from pipefollow.files.compile_cache import configure_numba_cache

configure_numba_cache()  # before any compiled module of this package is decorated
