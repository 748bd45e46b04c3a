"""Widgets of the operator HMI."""
