"""Reproductions of the five papers' tables and figures: ``skytrack reproduce 000|001|002|003|004|all``."""
