"""Deployment: a trained controller exported to run outside Python (ONNX). Depends on `learning`."""
