"""The FE plant: an OpenSees model (Python or Tcl) built, stepped under rlc's time loop and pushed over."""
