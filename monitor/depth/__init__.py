"""The depth view: depth maps from files or an ONNX network, the prior, the retrieval of S.

- :mod:`~monitor.depth.files`: depth maps on disk (``.npy`` metres, 16-bit PNG) and folders;
- :mod:`~monitor.depth.onnx_model`: metric depth from a user-supplied ONNX model;
- :mod:`~monitor.depth.prior`: the inverse-depth prior of training frames;
- :mod:`~monitor.depth.retrieval`: the paper's retrieval of safety-critical objects S;
- :mod:`~monitor.depth.geometric`: the geometric view: objects standing on the road inside
  the driving corridor, from the camera's intrinsics and mounting.
"""
