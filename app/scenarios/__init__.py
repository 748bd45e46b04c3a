"""Scenario runners: whole simulations of a plant with its controller in a sea state (the crane head in
waves, TAC paper §9–10; the Motion-Lab's vessel-to-vessel motion compensation), for the CLI, the
studies and the engines."""
