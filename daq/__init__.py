"""wheelsoil.daq"""
