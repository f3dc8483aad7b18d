"""A virtual scene and structured-light scanner: the ground truth every test, demo and study uses.

shapes: procedural closed meshes (car, figurine, L-block, platform, symmetric shapes for matcher tests);
clay: local lumps and carvings; scene: objects placed in the robot base frame B; raster: numpy
z-buffer; scanner: range images with noise, quantisation and occlusion; truth: U, V, W as JSON;
toolpath_sample: a finishing pass over the workpiece in its model frame X.
"""
