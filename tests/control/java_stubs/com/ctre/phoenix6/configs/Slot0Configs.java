// motorlab test stub, written from the vendor's public API signatures (no vendor code): compile-time only.
package com.ctre.phoenix6.configs;
public class Slot0Configs {
    public double kP, kI, kD, kS, kV, kA, kG;
}
