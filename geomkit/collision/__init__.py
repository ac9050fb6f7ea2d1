"""Collision and distance of meshed bodies: Body, collide, motion, scenes."""
