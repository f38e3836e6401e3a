"""Compensation of RAPID programs: resolve target poses, predict, rewrite."""
