"""Independent reference implementations (test oracles, benchmark references)."""
