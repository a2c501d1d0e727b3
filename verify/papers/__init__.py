"""The checks `garant verify` runs against the papers.

000 (stand_000, section6), 001 (norm_001), 003 (redundancy_003), certificates.
"""
