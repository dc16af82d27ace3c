/* motorlab JVM test: the INA219 driver's register arithmetic against the data sheet (SBOS448G). */
package org.firstinspires.ftc.teamcode.motorlab.sim;

import org.firstinspires.ftc.teamcode.motorlab.Ina219;

/** Prints "ok" or throws: configuration words, calibration, refusal of impossible parameters. */
public final class RegisterCheck {
    private RegisterCheck() {
    }

    private static void expect(boolean condition, String what) {
        if (!condition) {
            throw new AssertionError(what);
        }
    }

    public static void main(String[] argv) {
        Ina219.Parameters p = new Ina219.Parameters();
        // The power-on value 0x399F: 32 V range, ±320 mV, 12-bit bus and shunt, continuous (8.6.2.1).
        p.busRange = Ina219.BusRange.FSR_32V;
        p.busAdc = Ina219.Adc.BITS_12;
        p.shuntAdc = Ina219.Adc.BITS_12;
        expect(Ina219.configurationWord(p) == 0x399F, "configuration word of the reset state");
        // motorlab's default: 16 V range, ±320 mV, 2-sample averages: 0x1CCF.
        expect(Ina219.configurationWord(new Ina219.Parameters()) == 0x1CCF, "default configuration word");
        // Calibration example (8.5.1): 0.1 Ω and a 100 µA LSB give 4096.
        expect(Ina219.calibrationFor(0.1, 32767 * 100e-6) == 4096, "calibration 4096");
        expect(Ina219.calibrationFor(0.1, 3.2) % 2 == 0, "calibration bit 0 is void");
        // 3.3 A through 0.1 Ω is beyond ±320 mV; a 20 V limit is beyond the 16 V range.
        boolean refused = false;
        try {
            Ina219.Parameters q = new Ina219.Parameters();
            q.maxExpectedCurrent = 3.3;
            new Ina219(new SimIna219(new SimHub(new Plant(), 1), 1), true).configure(q);
        } catch (IllegalArgumentException e) {
            refused = true;
        }
        expect(refused, "a current beyond the shunt range is refused");
        refused = false;
        try {
            Ina219.Parameters q = new Ina219.Parameters();
            q.maxBusVoltage = 20;
            new Ina219(new SimIna219(new SimHub(new Plant(), 1), 1), true).configure(q);
        } catch (IllegalArgumentException e) {
            refused = true;
        }
        expect(refused, "a bus limit above the 16 V range is refused");
        // Against the register-level emulation: configure() reads back what it wrote.
        Ina219 ina = new Ina219(new SimIna219(new SimHub(new Plant(), 1), 1), true);
        expect(ina.configure(new Ina219.Parameters()), "configuration read back");
        expect(ina.initialize(), "doInitialize() with the defaults");
        expect(Math.abs(ina.readCurrent()) < 0.01 && ina.readBusVoltage() < 0.1, "motor at rest: no current, no voltage");
        System.out.println("ok");
    }
}
