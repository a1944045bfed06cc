"""Buildings known from measurements: a vibration test's recordings (`recording`) and the state-space
model identified from them (`subspace`)."""
