"""Communication-aware information planning (Liu, Fu & Gao 2018): receding-horizon heading search that maximises
the Fisher information expected to reach the base station over the minimum-spanning-tree relay network."""
