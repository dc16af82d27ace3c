"""Heat: the winding's two-node thermal network, fitting it from a log, forecasting a stall, the heat warning analyses
add."""
