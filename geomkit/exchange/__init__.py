"""Files in and out: geomkit cases and geomdl JSON, point sets, scans, atomic writes."""
