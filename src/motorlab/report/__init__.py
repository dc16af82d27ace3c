"""The printable report (report.html) and its sections."""
