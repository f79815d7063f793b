"""Helpers shared by test modules of several folders (builders of logs, bags, rigs, models).

Test modules import from here, never from one another; nothing here is collected as a test.
"""
