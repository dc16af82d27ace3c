"""The session workflow: the session file, characterising its units, the fleet, the gearbox per unit, a simulated
session."""
