"""The estimation engine: least squares, its covariance and "not determined" rule, the output-error problem, its
simulator and noise model, held inputs, decimation. Imports only core types and the model."""
