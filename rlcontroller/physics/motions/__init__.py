"""What loads a building: ground motions (records, generators, the site-based model), wind, and their
spectra."""
