"""Independent physical field-test simulator (issue 11): reference terramechanics, vehicle dynamics, effects."""
