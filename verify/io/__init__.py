"""Readers and writers: positions CSV, raw accelerometer logs, tables and JSON."""
