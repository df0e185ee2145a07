"""On top of the pipeline, course material: ``diagnosis`` (chapter 4's experiments on the reward
net's failure), ``fov`` (choosing the camera's field of view), ``exercises`` (check functions)."""
