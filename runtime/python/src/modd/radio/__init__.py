"""modd-radio: a link emulator between the two ends of the MoDD link (a UDP
relay, or a relay between two pseudo-terminals) imposing a byte rate, a packet
size, random loss, latency, jitter and scheduled outages, from a seed."""
